"""The FMU host: a process of its own that runs one FMU instance for the master
(``python -m orchestrator.cosim.fmu_host REQUESTS_FD REPLIES_FD WORKDIR``), so that an FMU
which crashes or hangs ends this process, not the master.  The master's side is
:class:`orchestrator.cosim.hosted_instance.HostedFmuInstance`; the instance inside is an
ordinary :class:`~orchestrator.cosim.fmu_instance.FmuInstance` (or, for an FMI 3.0 FMU, its
:class:`~orchestrator.cosim.fmi3_instance.Fmi3Instance`; same calls, log and messages).

The protocol, over two pipes: every message is a header ``HEADER`` (kind or status, payload
length in bytes) and its payload.

* ``CALL``: JSON ``[method, args]``, one of :data:`METHODS` (``open`` first: instantiate,
  answered with the variables); answered ``OK`` with the result as JSON.
* ``STEP``: binary, the per-step path in one round trip: ``flags`` (int64: ``SET`` the
  inputs, ``STEP``, ``GET`` the outputs), ``t`` and ``h`` (float64), then the Real inputs
  (float64) and the Integer and Boolean inputs (int32) in the order of ``prepare``; answered
  ``OK`` with the outputs (float64, int32, int32) when ``GET``.
* ``EXIT``: no payload, no answer; the host frees nothing more and ends.

A failed call is answered ``FAILED`` with JSON ``{"kind", "message", "time", "log"}`` (the
error the instance raised), and the host serves on.  Before each FMI call it writes the
call's index in :data:`CALLS` into the one-byte file ``WORKDIR/call``: when the host dies,
the master reads there which call it died in.  The host's own output goes to
``WORKDIR/host.log``, which the master keeps in the error's log.
"""
from __future__ import annotations

import json
import mmap
import os
import struct
import sys
from dataclasses import astuple
from pathlib import Path

import numpy as np

#: every message's header: kind (request) or status (reply), payload length
HEADER = struct.Struct("<B3xI")
CALL, STEP, EXIT = 1, 2, 3
OK, FAILED = 0, 1
#: STEP flags
SET, DO_STEP, GET = 1, 2, 4
#: bytes of a STEP payload before the inputs: flags, t, h
STEP_HEAD = 24
#: the FMI calls the host marks (see the module docstring), by index
CALLS = ("fmi2Instantiate", "fmi2Set* of the parameters", "fmi2SetupExperiment and "
         "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Set* of the inputs",
         "fmi2DoStep", "fmi2Get* of the outputs", "fmi2GetFMUstate", "fmi2SetFMUstate",
         "fmi2FreeFMUstate", "fmi2Terminate and fmi2FreeInstance")
#: the same calls of an FMI 3.0 FMU
CALLS_FMI3 = ("fmi3InstantiateCoSimulation", "fmi3Set* of the parameters",
              "fmi3EnterInitializationMode", "fmi3ExitInitializationMode",
              "fmi3Set* of the inputs", "fmi3DoStep", "fmi3Get* of the outputs",
              "fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState",
              "fmi3Terminate and fmi3FreeInstance")
#: CALL methods -> the FMI call each makes (an index of CALLS)
METHODS = {"open": 0, "prepare": None, "set_parameters": 1, "enter_initialization": 2,
           "exit_initialization": 3, "get_state": 7, "set_state": 8, "free_state": 9,
           "take_warnings": None, "terminate": 10}
CALL_FILE, LOG_FILE = "call", "host.log"


def read_exactly(stream, view: memoryview) -> bool:
    """Fill ``view`` from the unbuffered ``stream``; False at end of file."""
    got = 0
    while got < len(view):
        n = stream.readinto(view[got:])
        if not n:
            return False
        got += n
    return True


def write_all(fd: int, data) -> None:
    view = memoryview(data).cast("B")
    while len(view):
        view = view[os.write(fd, view):]


def step_layout(n_real: int, n_int: int, n_bool: int):
    """Byte offsets of the Real, Integer and Boolean values and the end, after ``start``."""
    def offsets(start):
        real_end = start + 8 * n_real
        int_end = real_end + 4 * n_int
        return start, real_end, int_end, int_end + 4 * n_bool
    return offsets


def typed_views(buffer: np.ndarray, bounds):
    """float64, int32, int32 views of ``buffer`` (uint8) between the ``bounds`` offsets."""
    a, b, c, d = bounds
    return buffer[a:b].view(np.float64), buffer[b:c].view(np.int32), buffer[c:d].view(np.int32)


class Host:
    """The serving side: one FmuInstance, its saved states by number, the step buffers."""

    def __init__(self, workdir: Path):
        self.workdir = workdir
        self.instance = None
        self.states = {}
        call_file = workdir / CALL_FILE
        with open(call_file, "r+b") as f:
            self.mark = mmap.mmap(f.fileno(), 1)
        self.request = np.zeros(0, dtype=np.uint8)
        self.reply = np.zeros(HEADER.size, dtype=np.uint8)

    def _mark(self, call: int) -> None:
        self.mark[0] = call

    # -- CALL -----------------------------------------------------------------------------
    def call(self, method: str, args):
        if method not in METHODS:
            raise ValueError(f"unknown request {method!r}")
        if METHODS[method] is not None:
            self._mark(METHODS[method])
        return getattr(self, "_" + method)(*args)

    def _open(self, path, name, unzipdir):
        from .fmi3_instance import open_fmu

        self.instance = inst = open_fmu(path, name, unzipdir=unzipdir)
        return {"model_name": inst.model_name, "can_get_set_state": inst.can_get_set_state,
                "build_info": inst.build_info,
                "variables": [astuple(v) for v in inst.variables.values()]}

    def _prepare(self, inputs, outputs):
        inst = self.instance
        n = {t: len([x for x in outputs if inst.variables[x].type == t])
             for t in ("Real", "Integer", "Boolean")}
        out_bounds = step_layout(n["Real"], n["Integer"], n["Boolean"])(HEADER.size)
        self.reply = np.zeros(out_bounds[-1], dtype=np.uint8)
        HEADER.pack_into(self.reply, 0, OK, out_bounds[-1] - HEADER.size)
        inst.prepare(inputs, outputs, *typed_views(self.reply, out_bounds))
        in_bounds = step_layout(len(inst.real_in), len(inst.int_in), len(inst.bool_in))(
            STEP_HEAD)
        self.request = np.zeros(in_bounds[-1], dtype=np.uint8)
        self.flags = self.request[:8].view(np.int64)
        self.times = self.request[8:STEP_HEAD].view(np.float64)
        self.inputs = typed_views(self.request, in_bounds)
        return None

    def _set_parameters(self, values):
        self.instance.set_parameters(values)

    def _enter_initialization(self, start, stop):
        self.instance.enter_initialization(start, stop)

    def _exit_initialization(self):
        self.instance.exit_initialization()

    def _get_state(self):
        number = len(self.states) + 1
        while number in self.states:
            number += 1
        self.states[number] = self.instance.get_state()
        return number

    def _set_state(self, number):
        self.instance.set_state(self.states[number])

    def _free_state(self, number):
        self.instance.free_state(self.states.pop(number))

    def _take_warnings(self):
        return self.instance.take_warnings()

    def _terminate(self):
        if self.instance is not None:
            self.instance.terminate()

    # -- STEP -----------------------------------------------------------------------------
    def step(self) -> bool:
        """Serve the STEP request in ``self.request``; True when it has outputs to send."""
        inst = self.instance
        flags = int(self.flags[0])
        if flags & SET:
            inst._copy_in(*self.inputs)
            self._mark(4)
            inst.set_inputs()
        if flags & DO_STEP:
            self._mark(5)
            inst.do_step(float(self.times[0]), float(self.times[1]))
        if flags & GET:
            self._mark(6)
            inst.get_outputs()
            return True
        return False


def _failure(exc: BaseException) -> bytes:
    from ..errors import NavfmuError, SimulationError, SimulationTerminated, WiringError

    kind = ("terminated" if isinstance(exc, SimulationTerminated) else
            "simulation" if isinstance(exc, SimulationError) else
            "wiring" if isinstance(exc, WiringError) else
            "navfmu" if isinstance(exc, NavfmuError) else "internal")
    text = str(exc) if kind != "internal" else f"{type(exc).__name__}: {exc}"
    body = {"kind": kind, "message": text, "time": getattr(exc, "time", None),
            "log": list(getattr(exc, "log", ()))}
    payload = json.dumps(body).encode("utf-8")
    return HEADER.pack(FAILED, len(payload)) + payload


def serve(requests, replies: int, host: Host) -> None:
    """Answer requests until EXIT or the master's end of the pipe."""
    header = bytearray(HEADER.size)
    empty = HEADER.pack(OK, 0)
    while read_exactly(requests, memoryview(header)):
        kind, length = HEADER.unpack(header)
        if kind == EXIT:
            return
        try:
            if kind == STEP:
                if not read_exactly(requests, memoryview(host.request)[:length]):
                    return
                write_all(replies, host.reply if host.step() else empty)
                continue
            body = bytearray(length)
            if not read_exactly(requests, memoryview(body)):
                return
            method, args = json.loads(body)
            payload = json.dumps(host.call(method, args)).encode("utf-8")
            write_all(replies, HEADER.pack(OK, len(payload)) + payload)
        except Exception as exc:
            write_all(replies, _failure(exc))


def _die_with_parent() -> None:
    """On Linux: be killed when the master ends, whatever it ends by (a hung FMU would
    otherwise outlive a master killed with SIGKILL)."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes
    import signal

    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def main(argv) -> None:
    _die_with_parent()
    requests_fd, replies_fd, workdir = int(argv[0]), int(argv[1]), Path(argv[2])
    if os.getppid() == 1:      # the master ended before the line above took effect
        return
    with open(requests_fd, "rb", buffering=0) as requests:
        serve(requests, replies_fd, Host(workdir))
    # the instance's shared library stays loaded; the master removes WORKDIR


if __name__ == "__main__":
    main(sys.argv[1:])
