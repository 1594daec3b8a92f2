"""Do the report pages fit the window? (issue 26: every column visible at 1280 px, or a table
that scrolls inside its own box; the first screen keeps the summary and the preview).

Makes a one-BRDF report and a two-BRDF batch (``shrm report --quick``), opens every page
(``report.html`` of each material, the batch ``index.html``) in headless chromium at each
``--widths`` × 800 px and prints, per page and width, the document's ``scrollWidth`` against the
window's ``clientWidth`` (equal: the page never scrolls sideways), the elements that stick out
of the page (outside any box that scrolls or clips), how far down the Summary and the Preview
headings start (both on the first screen: ≤ 800 px), and how many of the first table's columns
are in view before any sideways scrolling.

To compare with an older checkout, run this script with ``PYTHONPATH`` pointing at a folder that
holds it as ``shrmkit`` (the reports are made with ``shrmkit.cli.main`` through
``sys.executable``). Needs ``chromium`` on the PATH.

Usage::

    python benchmarks/report_layout.py [--widths 1280 1024] [--out DIR] [--keep]
"""

from __future__ import annotations

import argparse
import html
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

#: the console script's code (``console_main``; an older checkout without it: ``main``)
SHRM = [sys.executable, "-c", "import sys; from shrmkit.cli import main as m; "
        "sys.exit(m.console_main() if hasattr(m, 'console_main') else m.main())"]

#: (folder, BRDF arguments) of the two runs
RUNS = (("one", ["microfacet:sigma=0.1"]), ("batch", ["microfacet:sigma=0.1", "phong:s=30"]))

#: appended to a copy of each page: what the page measures of itself once laid out
_PROBE = """
<script>
window.addEventListener('load', function () { setTimeout(function () {
  var doc = document.documentElement, W = doc.clientWidth, over = [];
  function boxed(e) { for (var p = e.parentElement; p; p = p.parentElement) {
    var s = getComputedStyle(p).overflowX; if (s === 'auto' || s === 'scroll' || s === 'hidden') return true; }
    return false; }
  document.querySelectorAll('body *').forEach(function (e) {
    var r = e.getBoundingClientRect();
    if (r.right > W + 0.5 && !boxed(e) && e.id !== 'LAYOUT')
      over.push(e.tagName.toLowerCase() + ' to ' + Math.round(r.right));
  });
  var first = document.querySelector('table');
  var ths = first ? Array.from(first.querySelectorAll('th')) : [];
  var shown = ths.filter(function (th) { return th.getBoundingClientRect().right <= W + 0.5; }).length;
  var tops = {};
  document.querySelectorAll('h2').forEach(function (h) {
    tops[h.textContent] = Math.round(h.getBoundingClientRect().top); });
  var out = document.createElement('pre'); out.id = 'LAYOUT';
  out.textContent = JSON.stringify({scrollWidth: doc.scrollWidth, clientWidth: W, over: over, tops: tops,
                                    columns: shown + '/' + ths.length});
  document.body.appendChild(out);
}, 300); });
</script>
"""


def measure(page: Path, width: int, chromium: str) -> dict:
    """The probe's numbers for ``page`` at ``width`` × 800 px."""
    probe = page.with_name(f".layout_{page.name}")
    probe.write_text(page.read_text(encoding="utf-8") + _PROBE, encoding="utf-8")
    try:
        dom = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", f"--window-size={width},800",
                              "--virtual-time-budget=4000", "--dump-dom", probe.resolve().as_uri()],
                             capture_output=True, text=True, timeout=180).stdout
    finally:
        probe.unlink()
    m = re.search(r'<pre id="LAYOUT">(.*?)</pre>', dom, re.S)
    if not m:
        raise SystemExit(f"report_layout: chromium gave no measurement for {page}")
    return json.loads(html.unescape(m.group(1)))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--widths", type=int, nargs="+", default=[1280, 1024])
    parser.add_argument("--out", type=Path, help="folder for the reports (default: a temporary one)")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = parser.parse_args()
    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if chromium is None:
        print("report_layout: chromium not found on the PATH", file=sys.stderr)
        return 2
    root = args.out or Path(tempfile.mkdtemp(prefix="report_layout_"))
    for folder, brdfs in RUNS:
        subprocess.run([*SHRM, "report", "-q", "--quick", *brdfs, "--out", str(root / folder)], check=True)
    pages = sorted(root.glob("*/*/report.html")) + sorted(root.glob("batch/index.html"))
    print(f"{'page':42s} {'width':>5s} {'scrollWidth':>11s} {'clientWidth':>11s} {'Summary':>8s} "
          f"{'Preview':>8s} {'columns':>8s}  sticking out")
    worst = 0
    for page in pages:
        for width in args.widths:
            m = measure(page, width, chromium)
            worst = max(worst, m["scrollWidth"] - m["clientWidth"])
            tops = m["tops"]
            print(f"{str(page.relative_to(root)):42s} {width:5d} {m['scrollWidth']:11d} {m['clientWidth']:11d} "
                  f"{tops.get('Summary', '—')!s:>8s} {tops.get('Preview', '—')!s:>8s} {m['columns']:>8s}  "
                  f"{', '.join(m['over'][:4]) or '—'}")
    print(f"largest sideways overflow of a page: {worst} px")
    if args.out is None and not args.keep:
        shutil.rmtree(root)
    return 0


if __name__ == "__main__":
    sys.exit(main())
