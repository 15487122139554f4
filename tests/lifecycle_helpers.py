"""Real ``savant run`` subprocesses for the lifecycle tests: started with a test pause
(``SAVANT_TEST_PAUSE_AT``, :mod:`savant_cli.lifecycle`), waited for at that stage, then
signalled, killed or left to finish."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: Longest wait for a stage (s): the first run of a session compiles the plant.
STAGE_TIMEOUT_S = 900.0


@dataclass
class Done:
    code: int
    stdout: str
    stderr: str


def env(pause_at: str | None = None) -> dict[str, str]:
    """The environment of a child ``savant``: this checkout first on the path, no
    pause unless asked."""
    e = dict(os.environ)
    e["PYTHONPATH"] = os.pathsep.join([str(REPO), e.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    e.pop("SAVANT_TEST_PAUSE_AT", None)
    e["COLUMNS"] = "200"
    if pause_at:
        e["SAVANT_TEST_PAUSE_AT"] = pause_at
    return e


def savant(*args: str, cwd: Path | None = None, timeout: float = STAGE_TIMEOUT_S) -> Done:
    """Run ``savant ARGS`` to its end."""
    p = subprocess.run([sys.executable, "-m", "savant_cli.cli", *args], cwd=cwd, env=env(), capture_output=True,
                       text=True, timeout=timeout)
    return Done(p.returncode, p.stdout, p.stderr)


class Paused:
    """``savant ARGS`` started with the test pause at ``stage``; :meth:`wait` returns
    once it says it is paused there."""

    def __init__(self, stage: str, *args: str, cwd: Path | None = None) -> None:
        self.stage = stage
        self.proc = subprocess.Popen([sys.executable, "-m", "savant_cli.cli", *args], cwd=cwd, env=env(stage),
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     start_new_session=True)  # a signal to it alone, as a terminal's to its group
        self._err: list[str] = []

    def wait(self) -> "Paused":
        deadline = time.monotonic() + STAGE_TIMEOUT_S
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self._err.append(line)
            if f"paused at {self.stage}" in line:
                return self
            if time.monotonic() > deadline:
                break
        out, err = self.proc.communicate(timeout=60)
        raise AssertionError(f"never paused at {self.stage} (exit {self.proc.returncode}):\n{''.join(self._err)}{err}")

    def signal(self, sig: int) -> Done:
        """Send ``sig`` to its process group and collect what follows."""
        os.killpg(self.proc.pid, sig)
        return self.finish()

    def resume(self, timeout: float = 900.0) -> Done:
        """Let it go on from the pause (SIGUSR1) and collect its end."""
        self.proc.send_signal(signal.SIGUSR1)
        return self.finish(timeout)

    def finish(self, timeout: float = 300.0) -> Done:
        out, err = self.proc.communicate(timeout=timeout)
        return Done(self.proc.returncode, out, "".join(self._err) + err)

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.communicate(timeout=60)


def after_pause(text: str) -> str:
    """What a paused process printed after its pause line."""
    return text.split("(SAVANT_TEST_PAUSE_AT)\n", 1)[-1]


def tree(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}
