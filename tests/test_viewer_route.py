"""How a recording is opened: the hint ``shipgym run --record`` prints (``rerun PATH`` with a
display, rerun's web viewer without one)."""

import sys

import pytest

from shipgym.cli import main
from shipgym.viz import viewer_hint, web_viewer_url
from shipgym.viz.viewer import has_display, serve_web_command

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
