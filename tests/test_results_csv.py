"""The results CSV's text (orchestrator.results.run_results.write_csv_table) read back by readers
that are
not the writer: Python's csv module + float() (correctly rounded), numpy.loadtxt through
Results.from_csv; Python's repr (shortest round trip, its own algorithm) for the digit count."""

import csv
import io
import subprocess
import sys

import numpy as np
import pytest

from orchestrator.results import run_results as results_module
from orchestrator.results.run_results import Results, write_csv_table

SPECIAL = [np.nan, np.inf, -np.inf, -0.0, 0.0, 5e-324, -5e-324, 2.2250738585072014e-308,
           1.7976931348623157e308, -1.7976931348623157e308, 2.0 ** 53 + 2, 2.0 ** 53 - 1,
           2.0 ** 63, 3.0, -42.0, 1e16, 1e22, 1e23, 0.1, 1 / 3, 1e-7, 123456789.125]


def _values():
    """The special values, then 4000 float64 of random bit patterns (every exponent)."""
    rng = np.random.default_rng(14)
    bits = rng.integers(0, 2 ** 63, size=4000, dtype=np.int64).astype(np.uint64)
    bits[::2] |= np.uint64(1 << 63)                    # negative half
    random = bits.view(np.float64)
    random = random[np.isfinite(random)]
    return np.concatenate([SPECIAL, random])


def _results(values, width=3):
    """Results whose time column and data columns hold ``values`` (rows of ``width``)."""
    values = np.resize(values, (-(-len(values) // width) * width)).reshape(-1, width)
    return Results(time=values[:, 0].copy(), data={"comp": values[:, 1:].copy()},
                   columns={"comp": ["a", "b"]}, units={"comp": ["m", ""]})


def _same_bits(a, b):
    return np.array_equal(np.asarray(a, dtype=np.float64).view(np.uint64),
                          np.asarray(b, dtype=np.float64).view(np.uint64))


def _digits(text):
    """Significant digits of a decimal text ('1.25e-3' -> 3, '3.0' -> 1)."""
    mantissa = text.lstrip("+-").lower().split("e")[0].replace(".", "")
    return len(mantissa.strip("0")) or 1


def test_every_float64_reads_back_bit_for_bit_with_python_float_and_from_csv(tmp_path):
    res = _results(_values())
    path = res.to_csv(tmp_path / "r.csv")
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["time [s]", "comp.a [m]", "comp.b"]
    text = [cell for row in rows[1:] for cell in row]
    back = np.array([float(cell) for cell in text])
    assert _same_bits(back, res.table().ravel())
    # the shortest text: as many significant digits as Python's repr (finite values)
    for cell, value in zip(text, res.table().ravel()):
        if np.isfinite(value):
            assert _digits(cell) == _digits(repr(float(value))), (cell, repr(float(value)))
    assert text[:5] == ["NaN", "inf", "-inf", "-0.0", "0.0"]
    loaded = Results.from_csv(path)
    assert _same_bits(loaded.time, res.time)
    assert _same_bits(loaded.data["comp"], res.data["comp"])


def test_rows_split_over_calls_and_blocks_give_the_bytes_of_one_write(monkeypatch):
    table = _results(_values(), width=5).table()
    titles = ["time [s]", "c.a", "c.b [m]", "c.c", "c.d"]
    one = io.BytesIO()
    write_csv_table(one, table, titles)
    monkeypatch.setattr(results_module, "CSV_BLOCK_VALUES", 7)     # blocks of one row
    chunked = io.BytesIO()
    write_csv_table(chunked, table[:0], titles)
    for first, last in [(0, 1), (1, 250), (250, 250), (250, len(table) - 1), (len(table) - 1,
                                                                              len(table))]:
        write_csv_table(chunked, table[first:last])
    assert chunked.getvalue() == one.getvalue()
    assert one.getvalue().count(b"\n") == len(table) + 1


def test_header_only_results_write_and_read_an_empty_table(tmp_path):
    res = _results(np.zeros(0))
    path = res.to_csv(tmp_path / "empty.csv")
    assert path.read_bytes() == b"time [s],comp.a [m],comp.b\n"
    back = Results.from_csv(path)
    assert back.time.shape == (0,) and back.data["comp"].shape == (0, 2)


def test_commands_and_workers_do_not_import_polars_until_a_csv_is_written():
    code = (
        "import sys, orchestrator.cli, orchestrator.campaigns.campaign, "
        "orchestrator.results.recorder, "
        "orchestrator.cli.run_command; print('polars' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("bad", [b"time [s],c.a\n1.0,abc\n", b"time [s],c.a\n1.0\n"])
def test_a_damaged_csv_is_one_error_naming_the_file(tmp_path, bad):
    path = tmp_path / "bad.csv"
    path.write_bytes(bad)
    with pytest.raises(results_module.NavfmuError, match="bad.csv"):
        Results.from_csv(path)
