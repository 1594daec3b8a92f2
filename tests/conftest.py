"""Shared fixtures: the real data in ../shared/data (skipped with a clear message if absent), the
offscreen OpenGL probe, one ``shrm demo`` run, and headless chromium for the WebGL2 pages.

Under pytest-xdist (``-n 2``, its default ``--dist load``) a test **class** is one unit of work:
its tests run one after the other on one worker, so a costly module-scoped fixture they share (a
batch of reports, a browser) is made once instead of once per worker (and again whenever a
worker's tests of that module are interleaved with other modules'). Every test outside a class
is its own unit, handed out one by one as with ``--dist load``. (``--dist loadgroup`` would be
the marker way, but with pytest 9.2 and xdist 3.8 it silently groups nothing: pytest-xdist
issue #1386.)

The browser driver: Debian's ``chromium`` (headless, SwiftShader WebGL2 through ANGLE),
commands on a pipe (``--remote-debugging-pipe``, fds 3 and 4, NUL-separated JSON), no extra
Python package; the ``chromium`` fixture skips with a message where it is absent (CI installs
it: ``.ci/apt-packages.txt``). Test modules cannot import a conftest: they get the
:class:`Browser` class from the ``browser_class`` fixture.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import importlib.util
import io
import json
import os
import select
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from PIL import Image

from shrmkit.render.offscreen import probe_offscreen

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


#: modules whose tests share a cache made on first use, run as one unit of work under xdist: the
#: import graph of tests/test_layers.py (1.6 s CPU to parse, once instead of once per worker)
ONE_UNIT_MODULES = frozenset({"tests/test_layers.py"})

#: expected seconds (setup + call + teardown) of the tests that take 1 s or more on the 2-core project
#: machine, ``{node id: seconds}``; written by ``benchmarks/suite_cpu.py --durations-out`` from a
#: whole run. A test that is not listed counts 0 s (3 s if marked ``slow``): a stale entry only
#: changes the order in which the tests are handed out, never what runs.
DURATIONS = Path(__file__).resolve().parent / "resources" / "test_durations.json"
SLOW_UNLISTED_SECONDS = 3.0


def work_unit(nodeid: str) -> str:
    """The unit of work under xdist a test belongs to: ``path::Class`` for the tests of a class,
    the module for those of ``ONE_UNIT_MODULES``, the node id itself for any other test."""
    path, _, rest = nodeid.partition("::")
    if path in ONE_UNIT_MODULES:
        return path
    names = rest.split("[", 1)[0].split("::")
    return f"{path}::{names[0]}" if len(names) > 1 else nodeid


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """xdist's ``load`` distribution with a test class as one unit of work (module docstring)."""
    if config.getvalue("dist") != "load":
        return None
    from xdist.scheduler import LoadScopeScheduling

    # the units go out in collection order, which pytest_collection_modifyitems made longest first
    # (``loadscope``'s own reorder would put the units with the most tests first instead)
    config.option.loadscopereorder = False

    class ClassScheduling(LoadScopeScheduling):
        """Units: :func:`work_unit`, handed out in collection order (longest expected first)."""

        def _split_scope(self, nodeid: str) -> str:
            return work_unit(nodeid)

    return ClassScheduling(config, log)


@pytest.hookimpl(wrapper=True)
def pytest_collection(session):
    """Collection with bytecode writing on, whatever ``PYTHONDONTWRITEBYTECODE`` says: pytest caches a
    test module's assertion rewrite only when ``sys.dont_write_bytecode`` is false, and without that
    cache every run (every xdist worker) re-parses and rewrites all ~130 test modules: 17.6 s CPU of
    collection per worker instead of 8.3 s on the project's 2-core machine, where the variable is set.
    The files go to the ``__pycache__`` folders git ignores; the flag is restored before any test runs."""
    saved = sys.dont_write_bytecode
    sys.dont_write_bytecode = False
    try:
        return (yield)
    finally:
        sys.dont_write_bytecode = saved


def pytest_collection_modifyitems(config, items):
    """Units of work (:func:`work_unit`) longest expected first (``DURATIONS``: the sum over a
    unit's tests; a stable sort, so otherwise collection order), but the tests that read the shared
    demo run after the first of them last. Under xdist the units are handed out in this order, so the
    long ones start early and the run ends on short tests on both workers (longest processing time
    first) instead of with one worker busy on a 25 s test while the other is idle."""
    expected = json.loads(DURATIONS.read_text()) if DURATIONS.is_file() else {}
    unit_seconds: dict[str, float] = {}
    for item in items:
        unlisted = SLOW_UNLISTED_SECONDS if item.get_closest_marker("slow") is not None else 0.0
        unit = work_unit(item.nodeid)
        unit_seconds[unit] = unit_seconds.get(unit, 0.0) + expected.get(item.nodeid, unlisted)
    first = {}
    for index, item in enumerate(items):
        first.setdefault(work_unit(item.nodeid), index)
    items.sort(key=lambda item: (-unit_seconds[work_unit(item.nodeid)], first[work_unit(item.nodeid)]))
    # The session-wide demo run (demo_run below) is made by the first worker to ask while the other
    # waits on its lock: its users after the first go last, so that no worker sits ~11 s idle on it.
    demo_users = [item for item in items if "demo_run" in getattr(item, "fixturenames", ())]
    for item in demo_users[1:]:
        items.remove(item)
        items.append(item)


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data; skips the test when a user's clone has no ../shared."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data folder {SHARED_DATA} not present (only in the project workspace)")
    return SHARED_DATA


@pytest.fixture(scope="session")
def benchmark_module() -> Callable[[str], ModuleType]:
    """``benchmark_module(name)``: the script ``benchmarks/NAME.py`` imported as the module ``NAME``, once
    per run (the tests that drive a benchmark's cheap cases or its self-test)."""
    def load(name: str) -> ModuleType:
        if name not in sys.modules:
            spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
            assert spec is not None and spec.loader is not None
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module  # its dataclasses look their module up there
            spec.loader.exec_module(module)
        return sys.modules[name]

    return load


_PROBE: list[tuple[bool, str]] = []


@pytest.fixture(scope="session")
def offscreen() -> str:
    """The VTK window class in use; skips the test when no offscreen float context can be made
    (probed once, in a subprocess)."""
    if not _PROBE:
        _PROBE.append(probe_offscreen())
    ok, message = _PROBE[0]
    if not ok:
        pytest.skip(message)
    return message


def _finishes(call: Callable[[], object], seconds: float = 10.0) -> tuple[bool, BaseException | None]:
    """Run ``call()`` in a daemon thread for at most ``seconds``: (finished, the exception it raised
    or None). A reader that blocks (a FIFO) or never ends (/dev/zero) shows as not finished."""
    result: list[BaseException | None] = []

    def target() -> None:
        try:
            call()
            result.append(None)
        except BaseException as err:  # noqa: BLE001 - reported to the test
            result.append(err)

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(seconds)
    return bool(result), (result[0] if result else None)


@pytest.fixture(scope="session")
def finishes() -> Callable[..., tuple[bool, BaseException | None]]:
    """``finishes(call, seconds=10)``: run ``call`` in a thread with a time limit, (finished,
    exception or None) — for readers that must refuse special files at once."""
    return _finishes


# ------------------------------------------------------------------------------------------
# one `shrm demo` run for the tests that check its outputs
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DemoRun:
    """``shrm demo --no-progress --size 64`` run by :func:`main` in the clean folder ``cwd`` (its
    default ``--out``, ./shrm-demo): exit code and what it printed on stdout."""

    cwd: Path
    code: int
    printed: str

    @property
    def out(self) -> Path:
        return self.cwd / "shrm-demo"


def _run_demo(cwd: Path) -> DemoRun:
    from shrmkit.cli.main import main

    cwd.mkdir(parents=True, exist_ok=True)
    printed = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(printed):
        patch.chdir(cwd)
        code = main(["demo", "--no-progress", "--size", "64"])
    return DemoRun(cwd, code, printed.getvalue())


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory) -> DemoRun:
    """The demo, run once per test session for every test that reads its outputs: under xdist
    the first worker to ask runs it under a file lock in the folder all workers of this run
    share, the others read what it wrote (xdist's documented pattern for session fixtures)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if worker is None:
        return _run_demo(tmp_path_factory.mktemp("demo"))
    shared = tmp_path_factory.getbasetemp().parent / f"demo-{os.environ.get('PYTEST_XDIST_TESTRUNUID', 'run')}"
    shared.mkdir(exist_ok=True)
    record = shared / "run.json"
    with open(shared / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if not record.exists():
                run = _run_demo(shared / "cwd")
                record.write_text(json.dumps({"code": run.code, "printed": run.printed, "by": worker}))
            saved = json.loads(record.read_text())
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    return DemoRun(shared / "cwd", saved["code"], saved["printed"])


# ------------------------------------------------------------------------------------------
# headless chromium over the DevTools protocol
# ------------------------------------------------------------------------------------------

CHROMIUM_FLAGS = ("--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--hide-scrollbars", "--mute-audio", "--no-first-run")


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    """One headless chromium driven over the DevTools pipe (``FLAGS``: its command-line flags)."""

    FLAGS = CHROMIUM_FLAGS

    def __init__(self, exe: str, width: int, height: int, timeout: float = 60.0, flags: tuple[str, ...] = ()) -> None:
        to_browser_r, to_browser_w = os.pipe()
        from_browser_r, from_browser_w = os.pipe()
        # move the child's ends above fd 4 so that dup2 onto 3 and 4 never closes them first
        child_r, child_w = (fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in (to_browser_r, from_browser_w))
        os.close(to_browser_r)
        os.close(from_browser_w)

        def wire() -> None:
            os.dup2(child_r, 3)
            os.dup2(child_w, 4)

        self.proc = subprocess.Popen(
            [exe, *CHROMIUM_FLAGS, *flags, "--remote-debugging-pipe", f"--window-size={width},{height}",
             "about:blank"],
            close_fds=False, preexec_fn=wire, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
        os.close(child_r)
        os.close(child_w)
        self.out = os.fdopen(to_browser_w, "wb", buffering=0)
        self.inp = from_browser_r
        self.timeout = timeout
        self.buffer = b""
        self.last_id = 0
        page = next(t for t in self.call("Target.getTargets")["targetInfos"] if t["type"] == "page")
        self.session = self.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)["sessionId"]
        self.call("Page.enable", session=True)
        self.call("Emulation.setDeviceMetricsOverride", session=True, width=width, height=height,
                  deviceScaleFactor=1, mobile=False)

    def _message(self) -> dict:
        deadline = time.monotonic() + self.timeout
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.inp], [], [], left)[0]:
                raise TimeoutError("chromium did not answer")
            chunk = os.read(self.inp, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed the DevTools pipe")
            self.buffer += chunk
        text, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(text)

    def call(self, method: str, session: bool = False, **params) -> dict:
        self.last_id += 1
        message = {"id": self.last_id, "method": method, "params": params}
        if session:
            message["sessionId"] = self.session
        self.out.write(json.dumps(message).encode() + b"\0")
        while True:
            reply = self._message()
            if reply.get("id") == self.last_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]

    def evaluate(self, expression: str, await_promise: bool = False):
        result = self.call("Runtime.evaluate", session=True, expression=expression, returnByValue=True,
                           awaitPromise=await_promise)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def wait(self, expression: str, what: str) -> None:
        deadline = time.monotonic() + self.timeout
        while not self.evaluate(expression):
            if time.monotonic() > deadline:
                raise TimeoutError(f"page never got {what}")
            time.sleep(0.05)

    def open(self, url: str, element_ids: list[str]) -> dict[str, str]:
        """Navigate to ``url``, wait until every viewer ``element_ids`` is ready or shows its
        fallback; their states."""
        self.call("Page.navigate", session=True, url=url)
        ids = json.dumps(element_ids)
        self.wait(f"{ids}.every(id => {{ const r = document.getElementById(id);"
                  " return !!r && ['ready', 'fallback'].includes(r.dataset.state); })", "every viewer state")
        return self.evaluate(f"Object.fromEntries({ids}.map(id => [id, document.getElementById(id).dataset.state]))")

    def screenshot(self, selector: str) -> np.ndarray:
        """The element scrolled into view, two frames later, as a screenshot (H, W, 3) uint8 of its box."""
        sel = json.dumps(selector)
        self.evaluate(f"document.querySelector({sel}).scrollIntoView({{block: 'center'}})")
        self.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))", await_promise=True)
        box = self.evaluate(f"(() => {{ const b = document.querySelector({sel}).getBoundingClientRect();"
                            " return [b.x + window.scrollX, b.y + window.scrollY, b.width, b.height]; })()")
        x, y, w, h = box
        png = base64.b64decode(self.call("Page.captureScreenshot", session=True, format="png",
                                         clip={"x": x, "y": y, "width": w, "height": h, "scale": 1},
                                         captureBeyondViewport=False)["data"])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))

    def view_frame(self, hash_params: str, element_id: str = "shrm-view") -> np.ndarray:
        """Set the URL hash of a view page, wait for the frame its viewer draws for it, and return
        the whole page as a screenshot (H, W, 3) uint8."""
        el = f"document.getElementById({json.dumps(element_id)})"
        frames = self.evaluate(f"{el}.dataset.frames")
        self.evaluate(f"location.hash = {json.dumps(hash_params)}")
        self.wait(f"{el}.dataset.frames !== {json.dumps(frames)}", "a new frame")
        self.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))", await_promise=True)
        png = base64.b64decode(self.call("Page.captureScreenshot", session=True, format="png")["data"])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))

    def close(self) -> None:
        try:
            self.call("Browser.close")
        except (RuntimeError, TimeoutError, OSError):
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.out.close()
        os.close(self.inp)


@pytest.fixture(scope="session")
def browser_class() -> type[Browser]:
    """The :class:`Browser` driver (test modules cannot import a conftest)."""
    return Browser


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of the chromium executable; skips the test where it is not installed."""
    exe = chromium_path()
    if exe is None:
        pytest.skip("chromium not installed (Debian package 'chromium', listed in .ci/apt-packages.txt): "
                    "the WebGL2 pages are not checked in a browser")
    return exe
