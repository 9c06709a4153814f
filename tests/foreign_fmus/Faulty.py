"""Test FMU written without navfmu: y integrates u + k + b over each step; at crash_at it
kills its process with SIGSEGV (or, with null_read, reads address 0), at hang_at it sleeps
for ever."""
import ctypes
import os
import signal
import time

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real


class Faulty(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u, self.k, self.b = 0.0, 0, False
        self.y, self.n, self.odd = 0.0, 0, False
        self.crash_at, self.hang_at, self.null_read = -1.0, -1.0, False
        for name in ("crash_at", "hang_at"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        self.register_variable(Boolean("null_read", causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Integer("k", causality=Fmi2Causality.input,
                                       variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("b", causality=Fmi2Causality.input,
                                       variability=Fmi2Variability.discrete))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(Integer("n", causality=Fmi2Causality.output,
                                       variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("odd", causality=Fmi2Causality.output,
                                       variability=Fmi2Variability.discrete))

    def do_step(self, current_time, step_size):
        if 0.0 <= self.crash_at <= current_time + 1e-9:
            if self.null_read:
                ctypes.string_at(0)
            os.kill(os.getpid(), signal.SIGSEGV)
        if 0.0 <= self.hang_at <= current_time + 1e-9:
            marker = os.environ.get("FAULTY_HANG_MARKER")
            if marker:
                open(marker, "w").close()
            while True:
                time.sleep(1.0)
        self.y += step_size * (self.u * 0.5 + self.k + (1.0 if self.b else 0.0)) + 1e-3
        self.n += 1
        self.odd = self.n % 2 == 1
        return True
