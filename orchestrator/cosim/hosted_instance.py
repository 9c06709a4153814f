"""An FMU run in a host process of its own behind the master's
:class:`~orchestrator.cosim.backends.Instance` interface: the master's side of
:mod:`orchestrator.cosim.fmu_host` (its docstring has the protocol).

The per-step path is one round trip: ``set_inputs`` only marks the inputs (the master's
buffers ``real_in``/``int_in``/``bool_in`` are views into the request itself, so the
exchange writes straight into it), ``do_step`` sends them with the step and receives the
outputs, and ``get_outputs`` after it is free.  Any other call first sends inputs still
marked (initialization: inputs set, then outputs read or initialization left).

What can go wrong in the host ends there and is reported in one line naming the component,
the FMI call and the simulated time (:class:`~orchestrator.errors.SimulationError`):

* it dies (a segfault, an abort, an exit): ``the FMU process died with SIGSEGV in
  fmi2DoStep at t = 12.3 s``;
* a call does not return within ``call_timeout`` seconds: the host is killed and the
  message says so;
* Ctrl-C or SIGTERM (pending at :mod:`orchestrator.cosim.interrupts`): the host is killed
  within :data:`POLL_S` and the command ends as interrupted.

Each time the host process ends, its folder (the extracted FMU, its output, the call
marker) is removed.
"""
from __future__ import annotations

import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time as _time
import weakref
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from . import interrupts
from .backends import Instance, VarInfo
from .fmi3_variables import fmi_version
from .fmu_host import (CALL, CALL_FILE, CALLS, CALLS_FMI3, DO_STEP, EXIT, FAILED, GET, HEADER,
                       LOG_FILE, OK, SET, STEP, STEP_HEAD, read_exactly, step_layout,
                       typed_views, write_all)
from .host_process import child_environment, ending
from ..errors import NavfmuError, SimulationError, SimulationTerminated, WiringError

#: how often a wait for the host looks for Ctrl-C / SIGTERM [s]
POLL_S = 0.1
#: how long an ending host may take to exit after EXIT before it is killed [s]
EXIT_GRACE_S = 5.0
#: lines of the host's own output kept in the error's log
LOG_LINES_KEPT = 40


class HostDied(Exception):
    """The host process ended while a call was waiting for its answer."""


class HostHung(Exception):
    """A call got no answer within the timeout."""


class _Host:
    """The host process, its two pipes and its folder; waits with a timeout and for
    signals, and cleans up however it ends."""

    def __init__(self):
        self.workdir = Path(tempfile.mkdtemp(prefix="navfmu_host_"))
        (self.workdir / CALL_FILE).write_bytes(b"\xff")
        requests_r, self.requests = os.pipe()
        self.replies_fd, replies_w = os.pipe()
        try:
            with open(self.workdir / LOG_FILE, "wb") as log, interrupts.ignored():
                self.proc = subprocess.Popen(
                    [sys.executable, "-m", "orchestrator.cosim.fmu_host", str(requests_r),
                     str(replies_w), str(self.workdir)],
                    pass_fds=(requests_r, replies_w), stdin=subprocess.DEVNULL, stdout=log,
                    stderr=log, env=child_environment())
        except BaseException:
            self.proc = None
            for fd in (requests_r, replies_w, self.replies_fd):
                os.close(fd)
            self.close()
            raise
        os.close(requests_r)
        os.close(replies_w)
        self.replies = open(self.replies_fd, "rb", buffering=0)
        self.poll = select.poll()
        self.poll.register(self.replies_fd, select.POLLIN | select.POLLHUP | select.POLLERR)

    def wait_reply(self, timeout: float, header: bytearray, interruptible: bool = True) -> None:
        """Wait for the next reply's header; raise :class:`HostHung` after ``timeout`` s,
        :class:`HostDied` if the host ends first; a pending Ctrl-C/SIGTERM kills the host
        (and raises it when ``interruptible``)."""
        deadline = _time.monotonic() + timeout
        while not self.poll.poll(POLL_S * 1000):
            if interrupts.pending():
                self.kill()
                if interruptible:
                    interrupts.check()
                raise HostDied()
            if _time.monotonic() > deadline:
                self.kill()
                raise HostHung()
        if not read_exactly(self.replies, memoryview(header)):
            raise HostDied()

    def read(self, view) -> None:
        if not read_exactly(self.replies, view):
            raise HostDied()

    def returncode(self) -> int:
        try:
            return self.proc.wait(timeout=EXIT_GRACE_S)
        except subprocess.TimeoutExpired:
            self.kill()
            return self.proc.returncode

    def last_call(self, calls=CALLS) -> Optional[str]:
        """The FMI call the host marked last (see :mod:`.fmu_host`), named from ``calls``."""
        try:
            index = (self.workdir / CALL_FILE).read_bytes()[0]
        except (OSError, IndexError):
            return None
        return calls[index] if index < len(calls) else None

    def output(self) -> list:
        try:
            text = (self.workdir / LOG_FILE).read_text(encoding="utf-8", errors="replace")
        except OSError:
            return []
        return text.splitlines()[-LOG_LINES_KEPT:]

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()

    def exit(self) -> None:
        """Ask the host to end, kill it if it does not."""
        if self.proc is not None and self.proc.poll() is None:
            try:
                write_all(self.requests, HEADER.pack(EXIT, 0))
                self.proc.wait(timeout=EXIT_GRACE_S)
            except (OSError, subprocess.TimeoutExpired):
                pass
        self.kill()

    def close(self) -> None:
        """Kill the host if it still runs, close the pipes, remove its folder (idempotent)."""
        self.kill()
        replies = getattr(self, "replies", None)
        if replies is not None and not replies.closed:
            replies.close()
        if self.requests is not None:
            try:
                os.close(self.requests)
            except OSError:
                pass
            self.requests = None
        shutil.rmtree(self.workdir, ignore_errors=True)


class HostedState:
    """An FMU state kept in the host (its number there)."""

    def __init__(self, number: int):
        self.number = number


class HostedFmuInstance(Instance):
    """An FMI 2.0 or 3.0 co-simulation FMU run in a host process of its own (module docstring);
    the same calls, statuses and messages as :class:`~.fmu_instance.FmuInstance`, plus the
    host's death, a call's timeout and Ctrl-C reported in one line."""

    def __init__(self, path, name: str, call_timeout: float):
        super().__init__()
        self.name = name
        self.path = Path(path)
        self.source = str(self.path)
        self.call_timeout = float(call_timeout)
        self.time: Optional[float] = None
        self._header = bytearray(HEADER.size)
        #: the names of the FMI calls for messages, by the FMU's FMI version
        self._calls = CALLS_FMI3 if fmi_version(self.path) == "3.0" else CALLS
        self._pending_set = False
        self._fresh = False
        self._busy = False
        self._host: Optional[_Host] = _Host()
        self._finalizer = weakref.finalize(self, self._host.close)
        try:
            info = self._call("open", str(self.path), name, str(self._host.workdir / "fmu"))
        except BaseException:
            self.terminate()
            raise
        self.model_name = info["model_name"]
        self.build_info = dict(info["build_info"], hosted=True)
        self.can_get_set_state = bool(info["can_get_set_state"])
        self.variables = {v[0]: VarInfo(*v) for v in info["variables"]}

    # -- the round trip -----------------------------------------------------------------
    def _failed(self, what: str, time: Optional[float], reason: str,
                after: str = "") -> SimulationError:
        host, self._host = self._host, None
        call = host.last_call(self._calls) or what
        log = tuple(host.output())
        host.close()
        self._finalizer.detach()
        when = f" at t = {time:.9g} s" if time is not None else ""
        return SimulationError(f"component '{self.name}' ({self.path.name}): {reason} in "
                               f"{call}{when}{after}", component=self.name, time=time, log=log)

    def _round_trip(self, request, what: str, time: Optional[float], into=None):
        """Send ``request``, wait for the reply and read its payload (into the memoryview
        ``into``, else a new bytearray, returned); the host's end or silence and a failed
        call raised as their errors.  ``_busy`` holds while a reply is owed."""
        host = self._host
        if host is None:
            raise SimulationError(f"component '{self.name}' ({self.path.name}): its FMU "
                                  f"process has ended", component=self.name, time=time)
        self._busy = True
        try:
            write_all(host.requests, request)
        except OSError:
            pass            # the host has ended: the wait below says how
        try:
            host.wait_reply(self.call_timeout, self._header)
            status, length = HEADER.unpack(self._header)
            body = into[:length] if into is not None and status == OK else bytearray(length)
            host.read(memoryview(body))
        except HostHung:
            raise self._failed(what, time, "the FMU process hung",
                               f": no answer within the call timeout of "
                               f"{self.call_timeout:g} s; killed") from None
        except HostDied:
            code = host.returncode()
            verb = "died with" if code < 0 else "ended with"
            raise self._failed(what, time, f"the FMU process {verb} {ending(code)}") from None
        self._busy = False
        if status == FAILED:
            raise self._error(json.loads(body))
        return body

    def _error(self, body) -> NavfmuError:
        kind, message = body["kind"], body["message"]
        if kind in ("simulation", "terminated"):
            cls = SimulationTerminated if kind == "terminated" else SimulationError
            return cls(message, component=self.name, time=body["time"], log=tuple(body["log"]))
        if kind == "wiring":
            return WiringError(message)
        if kind == "navfmu":
            return NavfmuError(message)
        return SimulationError(f"component '{self.name}' ({self.path.name}): the FMU host "
                               f"failed: {message}", component=self.name, time=self.time)

    def _call(self, method: str, *args) -> Any:
        if self._pending_set:
            self._exchange(SET, 0.0, 0.0)
        payload = json.dumps([method, list(args)]).encode("utf-8")
        return json.loads(self._round_trip(HEADER.pack(CALL, len(payload)) + payload,
                                           method.replace("_", " "), self.time))

    def _exchange(self, flags: int, t: float, h: float, time: Optional[float] = None) -> None:
        """One STEP request: set the marked inputs, step, read the outputs (per ``flags``)."""
        if self._pending_set:
            flags |= SET
        self._flags[0] = flags
        self._times[0], self._times[1] = t, h
        what = self._calls[5] if flags & DO_STEP else self._calls[6]
        if self._round_trip(self._request, what, self.time if time is None else time,
                            into=self._reply_bytes):
            self.real_out[:], self.int_out[:], self.bool_out[:] = self._replied
        self._pending_set = False
        self._fresh = bool(flags & GET)

    # -- preparation --------------------------------------------------------------------
    def _prepared(self) -> None:
        names = [n for t in ("Real", "Integer", "Boolean") for n in self.input_names[t]]
        outs = [n for t in ("Real", "Integer", "Boolean") for n in self.output_names[t]]
        self._call("prepare", names, outs)
        layout = step_layout(len(self.real_in), len(self.int_in), len(self.bool_in))
        bounds = layout(HEADER.size + STEP_HEAD)
        self._request = np.zeros(bounds[-1], dtype=np.uint8)
        HEADER.pack_into(self._request, 0, STEP, bounds[-1] - HEADER.size)
        self._flags = self._request[HEADER.size:HEADER.size + 8].view(np.int64)
        self._times = self._request[HEADER.size + 8:HEADER.size + STEP_HEAD].view(np.float64)
        self.real_in, self.int_in, self.bool_in = typed_views(self._request, bounds)
        out = step_layout(len(self.real_out), len(self.int_out), len(self.bool_out))(0)
        self._reply = np.zeros(out[-1], dtype=np.uint8)
        self._reply_bytes = memoryview(self._reply)
        self._replied = typed_views(self._reply, out)

    # -- life cycle ---------------------------------------------------------------------
    def set_parameters(self, values: Mapping[str, Any]) -> None:
        for name in values:
            self.variable(name, ("parameter", "input"))
        self._call("set_parameters", dict(values))

    def enter_initialization(self, start_time: float, stop_time: Optional[float]) -> None:
        self.time = start_time
        self._call("enter_initialization", start_time, stop_time)

    def exit_initialization(self) -> None:
        self._call("exit_initialization")

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        self._copy_in(real_values, int_values, bool_values)
        self._pending_set = True
        self._fresh = False

    def get_outputs(self):
        if not self._fresh or self._pending_set:
            self._exchange(GET, 0.0, 0.0)
        return self.real_out, self.int_out, self.bool_out

    def do_step(self, t: float, h: float) -> None:
        self._exchange(DO_STEP | GET, t, h, time=t)
        self.time = t + h

    def get_state(self) -> HostedState:
        return HostedState(self._call("get_state"))

    def set_state(self, state: HostedState) -> None:
        self._call("set_state", state.number)
        self._fresh = False

    def free_state(self, state: HostedState) -> None:
        self._call("free_state", state.number)

    def take_warnings(self):
        return self._call("take_warnings") if self._host is not None else []

    def terminate(self) -> None:
        """Terminate and free the instance in the host, end the host, remove its folder.
        Safe to call more than once and after any failure; never raises (a pending
        Ctrl-C ends the host at once and stays pending for the master's next safe point)."""
        host, self._host = self._host, None
        if host is None:
            return
        try:
            if self._busy:          # a call was cut short: its reply would come first
                host.kill()
            if host.proc is not None and host.proc.poll() is None:
                payload = json.dumps(["terminate", []]).encode("utf-8")
                write_all(host.requests, HEADER.pack(CALL, len(payload)) + payload)
                host.wait_reply(self.call_timeout, self._header, interruptible=False)
                host.exit()
        except (OSError, HostDied, HostHung):
            pass
        finally:
            host.close()
            self._finalizer.detach()


__all__ = ["HostedFmuInstance", "HostedState", "POLL_S"]
