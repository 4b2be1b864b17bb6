"""tools/bench/bench_ros_bridge.stop_launcher: the one stop (live and flood benchmarks) of a launch
in its own session: Ctrl-C first, the whole group killed when Ctrl-C is not enough."""

from __future__ import annotations

import signal
import subprocess
import sys

from tools.bench.bench_ros_bridge import stop_launcher

# Honours Ctrl-C as `chronav launch` does, by its own handler: a process started from a background
# job inherits SIGINT ignored, and Python then installs no KeyboardInterrupt handler of its own.
SLEEPER = ("import signal, time\nsignal.signal(signal.SIGINT, signal.default_int_handler)\nprint('ready', flush=True)\n"
           "while True: time.sleep(0.05)")
DEAF = "import signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\nprint('ready', flush=True)\nwhile True: time.sleep(0.05)"


def _spawn(code: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, start_new_session=True)


def test_ctrl_c_ends_a_launcher_that_honours_it() -> None:
    # Ctrl-C once its handler is in place (before, the signal would meet the inherited disposition).
    launcher = _spawn(SLEEPER)
    assert launcher.stdout is not None and launcher.stdout.readline() == b"ready\n"
    stop_launcher(launcher)
    assert launcher.returncode != 0 and launcher.returncode != -signal.SIGKILL


def test_a_launcher_deaf_to_ctrl_c_is_killed_after_the_grace() -> None:
    launcher = _spawn(DEAF)
    assert launcher.stdout is not None and launcher.stdout.readline() == b"ready\n"
    stop_launcher(launcher, grace_s=0.3)
    assert launcher.returncode == -signal.SIGKILL


def test_an_ended_launcher_is_left_alone() -> None:
    launcher = _spawn("pass")
    launcher.wait(timeout=30)
    stop_launcher(launcher)
    assert launcher.returncode == 0
