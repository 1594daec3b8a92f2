"""What the default path imports: a report's, a prefilter's and a render's modules load no SciPy
sub-package beyond what they use on every run (issue 22: start-up is a large part of a quick
report). The heavy ones are imported where a rarer path needs them (measured ~0.3-0.5 s CPU each
with SciPy's array-API layer): Gaussian-lobe fits (scipy.special, scipy.optimize), scattered
reciprocity (scipy.spatial), large light masks (scipy.ndimage)."""

import subprocess
import sys

HEAVY = ("scipy.special", "scipy.fft", "scipy.ndimage", "scipy.spatial", "scipy.linalg", "scipy.optimize",
         "scipy.sparse.linalg", "scipy.sparse.csgraph", "scipy.stats", "scipy.interpolate")


def _heavy_loaded(code: str) -> list[str]:
    """The heavy SciPy sub-packages loaded by a fresh interpreter running ``code`` (which prints the
    loaded ``scipy.*`` module names)."""
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return sorted({m for m in loaded for h in HEAVY if m == h or m.startswith(h + ".")})


def test_default_path_modules_import_no_heavy_scipy() -> None:
    code = ("import sys\n"
            "import shrmkit.cli.cmd_report, shrmkit.cli.report.collect, shrmkit.cli.report.writer\n"
            "import shrmkit.cli.cmd_prefilter, shrmkit.cli.cmd_render, shrmkit.render.vtk_renderer\n"
            "import shrmkit.analysis.orders, shrmkit.analysis.lights, shrmkit.analysis.baselines.methods\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('scipy.'))))")
    assert _heavy_loaded(code) == []


def test_prefilter_with_a_sun_imports_no_heavy_scipy() -> None:
    """A whole prefilter with a light taken out (builtin:sky's sun) and the order search."""
    code = ("import sys\n"
            "from shrmkit.analysis.shrm import prefilter\n"
            "m = prefilter('builtin:sky,height=32', 'microfacet:sigma=0.2', eps=0.1)\n"
            "assert m.has_lights\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('scipy.'))))")
    assert _heavy_loaded(code) == []


def test_a_report_without_plots_never_imports_matplotlib(tmp_path) -> None:
    """shrm report --no-plots (a census of a library, issue 22's report cost): every number and
    table, no matplotlib (its import is ~0.5 s CPU) and no SciPy (~0.3-0.4 s); the same report with
    plots draws them."""
    code = ("import sys\n"
            "from shrmkit.cli.main import main\n"
            "rc = main(['report', '--quick', 'phong:s=20', '--no-plots', '--preview', 'none', '--out', sys.argv[1],"
            " '-q', '--no-progress', '--models', 'lafortune'])\n"
            "print(rc, 'matplotlib' in sys.modules, 'scipy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "r")], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["0", "False", "False"]  # no SciPy at all either (the live view's lookups are numpy)
    assert not list((tmp_path / "r").rglob("plot_*.png"))
