"""``vtrack select INPUT``: drag the target's first box in a browser page; print and save it."""

from __future__ import annotations

import click

from vtrack.cli._messages import echo_stdout, note, stdout_failed, warn
from vtrack.cli._options import VtrackCommand, WholeNumber
from vtrack.cli._paths import INPUT
from vtrack.cli._signals import stopping_as_interrupted
from vtrack.params import MAX_FRAME_NUMBER


@click.command("select", cls=VtrackCommand)
@click.argument("input_spec", metavar="INPUT", type=INPUT)
@click.option("--frame", "frame", type=WholeNumber(0, MAX_FRAME_NUMBER), default=0,
              show_default=True,
              help="Frame shown first (0-based); the page steps back and forth from it.")
@click.option("--port", type=WholeNumber(0, 65535), default=0,
              help="Port on 127.0.0.1 to serve the page on. Default: a free one (printed).")
def command(input_spec: str, frame: int, port: int) -> None:
    """Pick the target's first box by dragging it on a frame of INPUT in a browser.

    Serves a page on 127.0.0.1 at a URL with a per-session secret path, printed when it
    starts (over SSH: ssh -L PORT:127.0.0.1:PORT HOST, then open that URL locally). The box
    is dragged on the frame or typed as x,y,w,h. On confirm, prints the --init value and writes
    it to the sidecar file that vtrack run and vtrack batch read when no --init is given:
    NAME.init.txt beside a video NAME.EXT, init.txt inside an image-sequence folder (stdin, a
    URL or a device has none). A box confirmed on a frame N other than 0 is printed as --start
    N --init x,y,w,h and not saved: the sidecar holds frame 0's box.
    """
    from vtrack.errors import InputError
    from vtrack.io.sidecar import format_box
    from vtrack.picker.frames import FrameStore
    from vtrack.picker.server import SelectionServer

    # SIGTERM (kill, timeout) as Ctrl-C: 'vtrack: interrupted', exit 143, as vtrack run
    with stopping_as_interrupted(), FrameStore(input_spec) as store:
        _refuse_frames_too_small(input_spec, store.info.width, store.info.height)
        if store.get(frame) is None:  # (at once when the input's frame count says so)
            raise InputError(f"{input_spec}: --frame {frame}: there is no such frame "
                             f"(frames 0..{store.count - 1})")
        server = SelectionServer(input_spec, store, frame, port)
        try:  # the page's address is the only way to it: unsaid, select would wait for ever
            click.echo(f"vtrack select: drag a box around the target at {server.url}  (Ctrl-C "
                       f"to cancel; over SSH: ssh -L {server.port}:127.0.0.1:{server.port} "
                       "HOST)", err=True)
        except (OSError, ValueError):
            raise SystemExit(1) from None
        if server.unreadable:
            warn(f"{server.unreadable}; the box you confirm replaces it")
        selection = server.wait()
    if selection.frame != 0:  # not saved: a sidecar box is frame 0's
        _print(f"--start {selection.frame} --init {format_box(selection.box)}", "it was not "
               "saved (the sidecar holds frame 0's box)")
        note("select", "not saved (the sidecar holds frame 0's box): the box was drawn on "
                       f"frame {selection.frame}; give both options to vtrack run")
        return
    if selection.sidecar is None:
        _print(f"--init {format_box(selection.box)}", f"it was not saved ({input_spec} has "
               "no sidecar file)")
        note("select", f"{input_spec} has no sidecar file (stdin, a URL or a device): give "
                       "the box to vtrack run as --init")
    else:
        _print(f"--init {format_box(selection.box)}", f"it is saved in {selection.sidecar}")
        note("select", f"saved in {selection.sidecar} (vtrack run and vtrack batch use it "
                       "when no --init is given)")


def _refuse_frames_too_small(input_spec: str, width: int, height: int) -> None:
    """InputError when frames of ``width`` x ``height`` hold no box vtrack run takes (a side
    under :data:`~vtrack.geometry.MIN_BOX_SIDE`): the page would refuse every box dragged on
    them, and wait for ever."""
    from vtrack.errors import InputError
    from vtrack.geometry import MIN_BOX_SIDE

    if min(width, height) < MIN_BOX_SIDE:
        raise InputError(f"{input_spec}: its frames are {width}x{height}, too small for the "
                         f"smallest box vtrack run tracks ({MIN_BOX_SIDE:g}x{MIN_BOX_SIDE:g} "
                         "pixels): there is no box to select")


def _print(line: str, kept: str) -> None:
    """``line``, the options for vtrack run, on stdout. When stdout's reader went away
    (``vtrack select clip.mp4 | true``) OutputBrokenError (one line, exit 1) gives ``line`` and
    ``kept`` (whether and where the box was saved) on stderr instead; stdout is then pointed
    at /dev/null, so the interpreter's last flush adds nothing. So too when stdout was closed
    before vtrack started (``vtrack select clip.mp4 >&-``: Python has no ``sys.stdout`` then,
    and click would print nothing without a word)."""
    from vtrack.errors import OutputBrokenError

    failure = echo_stdout(line)
    if failure is not None:
        raise OutputBrokenError(stdout_failed(failure, f"{line} was not printed there; {kept}"))
