"""What the default path imports: a report's, a prefilter's and a render's modules load no SciPy
sub-package beyond what they use on every run (issue 22: start-up is a large part of a quick
report). The heavy ones are imported where a rarer path needs them (measured ~0.3-0.5 s CPU each
with SciPy's array-API layer): Gaussian-lobe fits (scipy.special, scipy.optimize), scattered
reciprocity (scipy.spatial), large light masks (scipy.ndimage)."""

import subprocess
import sys

HEAVY = ("scipy.special", "scipy.fft", "scipy.ndimage", "scipy.spatial", "scipy.linalg", "scipy.optimize",
         "scipy.sparse.linalg", "scipy.sparse.csgraph", "scipy.stats", "scipy.interpolate")


def test_default_path_modules_import_no_heavy_scipy() -> None:
    code = ("import sys\n"
            "import shrmkit.cli.cmd_report, shrmkit.cli.report.collect, shrmkit.cli.report.writer\n"
            "import shrmkit.cli.cmd_prefilter, shrmkit.cli.cmd_render, shrmkit.render.vtk_renderer\n"
            "import shrmkit.analysis.orders, shrmkit.analysis.lights, shrmkit.analysis.baselines.methods\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('scipy.'))))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    heavy = sorted({m for m in loaded for h in HEAVY if m == h or m.startswith(h + ".")})
    assert heavy == [], heavy


def test_prefilter_with_a_sun_imports_no_heavy_scipy() -> None:
    """A whole prefilter with a light taken out (builtin:sky's sun) and the order search."""
    code = ("import sys\n"
            "from shrmkit.analysis.shrm import prefilter\n"
            "m = prefilter('builtin:sky,height=32', 'microfacet:sigma=0.2', eps=0.1)\n"
            "assert m.has_lights\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('scipy.'))))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    heavy = sorted({m for m in loaded for h in HEAVY if m == h or m.startswith(h + ".")})
    assert heavy == [], heavy
