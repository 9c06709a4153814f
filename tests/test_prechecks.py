"""The checks made before a run starts (orchestrator.running.prechecks), at their boundaries."""
import pytest

from orchestrator.errors import NavfmuError
from orchestrator.running.prechecks import (BYTES_PER_RECORDED_VALUE, check_memory,
                                            check_stop_time)


def test_precheck_boundaries():
    """--stop equal to the start is refused, a hair after it accepted; a recording of exactly
    the available memory is accepted, one value more refused."""
    with pytest.raises(NavfmuError, match="must be after the start time 2 s"):
        check_stop_time(2.0, 2.0)
    check_stop_time(2.0 + 1e-9, 2.0)
    check_stop_time(None, 2.0)
    check_memory(1000, 10, available=1000 * 10 * BYTES_PER_RECORDED_VALUE)
    with pytest.raises(NavfmuError, match="1001 rows x 10 variables"):
        check_memory(1001, 10, available=1000 * 10 * BYTES_PER_RECORDED_VALUE)
