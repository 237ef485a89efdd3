"""How a recording is opened: the hint ``shipgym run --record`` prints (``rerun PATH`` with a
display, rerun's web viewer without one), and that web-viewer route end to end in headless
Chromium (``tools/viewer_screenshot.py``; skipped without ``chromium`` on the PATH)."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shipgym.cli import main
from shipgym.viz import viewer_hint, web_viewer_url
from shipgym.viz.viewer import has_display, serve_web_command

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "tools" / "viewer_screenshot.py"
URL = "http://127.0.0.1:9090/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9876%2Fproxy"
FORWARD = "ssh -N -L 9090:127.0.0.1:9090 -L 9876:127.0.0.1:9876 USER@HOST"


@pytest.fixture
def no_display(monkeypatch):
    """Neither DISPLAY nor WAYLAND_DISPLAY (Linux: elsewhere a display is assumed)."""
    if not sys.platform.startswith("linux"):
        pytest.skip("the no-display check is Linux-specific")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)


@pytest.mark.parametrize("var", ["DISPLAY", "WAYLAND_DISPLAY"])
def test_with_a_display_the_native_viewer(no_display, monkeypatch, var):
    monkeypatch.setenv(var, ":0" if var == "DISPLAY" else "wayland-0")
    assert has_display()
    assert viewer_hint("runs/demo/harbour.rrd") == (
        "open the recording with: rerun runs/demo/harbour.rrd"
    )
    assert viewer_hint("my run.rrd") == "open the recording with: rerun 'my run.rrd'"


def test_without_a_display_the_web_viewer_route(no_display):
    assert not has_display()
    lines = viewer_hint("my runs/it's.rrd").splitlines()
    assert lines[0].startswith("open the recording with rerun's web viewer (no display")
    # the command, the address and the port forward each on a line of its own, to copy
    assert lines[1] == "  rerun --serve-web --bind 127.0.0.1 'my runs/it'\"'\"'s.rrd'"
    assert lines[3] == f"  {URL}"
    assert lines[5] == f"  {FORWARD}"
    assert len(lines) == 6


def test_an_empty_display_variable_is_no_display(no_display, monkeypatch):
    monkeypatch.setenv("DISPLAY", "")
    assert not has_display()
    assert "--serve-web" in viewer_hint("run.rrd")


@pytest.mark.parametrize("platform", ["darwin", "win32"])
def test_macos_and_windows_are_assumed_to_have_a_display(no_display, monkeypatch, platform):
    monkeypatch.setattr(sys, "platform", platform)
    assert has_display()
    assert viewer_hint("run.rrd") == "open the recording with: rerun run.rrd"
    assert viewer_hint("run.rrd", environ={}, platform="linux") != viewer_hint("run.rrd")


def test_the_address_names_the_grpc_server():
    """The bare web viewer (``http://127.0.0.1:9090``) shows rerun's Welcome page: the address
    carries the gRPC server that serves the recording, percent-encoded."""
    assert web_viewer_url() == URL
    assert web_viewer_url(8000, 8001) == (
        "http://127.0.0.1:8000/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A8001%2Fproxy"
    )
    assert serve_web_command("a.rrd") == "rerun --serve-web --bind 127.0.0.1 a.rrd"
    assert serve_web_command("a.rrd", web_port=8000, grpc_port=8001) == (
        "rerun --serve-web --bind 127.0.0.1 --web-viewer-port 8000 --port 8001 a.rrd"
    )


@pytest.mark.parametrize("display", [None, ":0"])
def test_shipgym_run_record_prints_the_route(tmp_path, no_display, monkeypatch, capsys, display):
    if display is not None:
        monkeypatch.setenv("DISPLAY", display)
    rrd = tmp_path / "sk run.rrd"
    argv = ["run", "station-keeping", "--seed", "0", "--no-progress", "--record", str(rrd)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert rrd.is_file()
    hint = viewer_hint(rrd)
    assert out.rstrip().endswith(hint)
    if display is None:
        assert f"rerun --serve-web --bind 127.0.0.1 '{rrd}'" in out and URL in out
    else:
        assert f"open the recording with: rerun '{rrd}'" in out and "--serve-web" not in out


# ---- the route end to end, in headless Chromium ---------------------------------------------
def _chromium():
    names = ("chromium", "chromium-browser", "google-chrome")
    return next(filter(None, map(shutil.which, names)), None)


def _leftovers():
    """Processes whose command line names the script's temporary folder (rerun serving the
    recording recorded there, Chromium with its profile there)."""
    found = []
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if "shipgym-viewer-" in cmd and "viewer_screenshot.py" not in cmd:
            found.append(f"{proc.name}: {cmd[:120]}")
    return found


needs_chromium = pytest.mark.skipif(
    _chromium() is None,
    reason="chromium is not on the PATH (Debian: apt-get install -y chromium): the headless "
    "web-viewer route is not checked",
)


@pytest.mark.slow
@needs_chromium
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="checks /proc for leftovers")
def test_the_web_viewer_route_shows_the_recording(tmp_path):
    """``tools/viewer_screenshot.py`` records a harbour run, serves it, opens the printed
    route in headless Chromium and sees the recording (the map), not rerun's Welcome page;
    nothing is left running (about 30 s on two cores)."""
    png = tmp_path / "viewer.png"
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--out", str(png), "--timeout", "150", "--settle", "30"],
        capture_output=True,
        text=True,
        timeout=400,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "saw the recording" in out.stdout, out.stdout
    assert "opening http://127.0.0.1:" in out.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert _leftovers() == []


@pytest.mark.slow
@needs_chromium
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="checks /proc for leftovers")
def test_ctrl_c_stops_rerun_and_chromium(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, str(SCRIPT), "--out", str(tmp_path / "v.png")],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        cwd=ROOT,
    )
    lines = []
    deadline = time.monotonic() + 120
    assert proc.stdout is not None
    for line in proc.stdout:  # until Chromium is loading the viewer
        lines.append(line)
        if line.startswith("opening") or time.monotonic() > deadline:
            break
    # interrupt as soon as Chromium runs beside rerun (a fixed wait let a fast viewer finish
    # its screenshot first: exit 0, nothing left to stop)
    until = time.monotonic() + 30.0
    while not any("chrom" in p for p in _leftovers()) and time.monotonic() < until:
        time.sleep(0.1)
    assert _leftovers(), "rerun and Chromium should be running now"
    os.kill(proc.pid, signal.SIGINT)
    rest, _ = proc.communicate(timeout=60)
    assert proc.returncode == 130, "".join(lines) + rest
    assert _leftovers() == []
