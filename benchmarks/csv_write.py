"""Wall time of writing (and reading) one results CSV: the writer of this checkout
(``Results.to_csv``, polars) against numpy's ``savetxt`` at ``%.17g`` (the writer before it),
alternating in one process on the table of a real run, and ``Results.from_csv``
(``numpy.loadtxt``) against ``polars.read_csv`` of the same file.

    navfmu run models/aircraft_500s --no-plots --out /tmp/a500
    python benchmarks/csv_write.py /tmp/a500/results.csv --rounds 5

Prints per writer and reader the median and the fastest of the rounds, and the ratios of the
medians; checks that both files read back as the same array.
"""
from __future__ import annotations

import argparse
import csv
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from checkouts import alternating

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from orchestrator.results.run_results import Results, atomic_write  # noqa: E402


def savetxt_17g(res: Results, path: Path) -> None:
    """``Results.to_csv`` before polars: atomically, header by csv.writer, rows by
    numpy.savetxt("%.17g")."""
    table = res.table()

    def write(f):
        csv.writer(f, lineterminator="\n").writerow(res.header())
        np.savetxt(f, table, fmt="%.17g", delimiter=",")

    atomic_write(path, write)


def polars_read(path: Path) -> np.ndarray:
    import polars as pl

    with open(path, newline="") as f:
        width = len(next(csv.reader([f.readline()])))
    frame = pl.read_csv(path, has_header=False, skip_rows=1,
                        schema={f"c{j}": pl.Float64 for j in range(width)})
    return frame.to_numpy()


def _timed(call) -> float:
    t0 = time.perf_counter()
    call()
    return time.perf_counter() - t0


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv", type=Path, help="a results.csv of a run")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    res = Results.from_csv(args.csv)
    table = res.table()
    print(f"{args.csv}: {table.shape[0]} rows x {table.shape[1]} columns")
    times = {"savetxt %.17g": [], "to_csv (polars)": [], "from_csv (loadtxt)": [],
             "polars.read_csv": []}
    with tempfile.TemporaryDirectory(prefix="navfmu-csv-") as tmp:
        old, new = Path(tmp) / "old.csv", Path(tmp) / "new.csv"
        t0 = time.perf_counter()
        import polars  # noqa: F401  (its import, once per process, timed apart)
        print(f"import polars: {time.perf_counter() - t0:.3f} s")
        writers = [("savetxt %.17g", lambda: savetxt_17g(res, old)),
                   ("to_csv (polars)", lambda: res.to_csv(new))]
        readers = [("from_csv (loadtxt)", lambda: Results.from_csv(new)),
                   ("polars.read_csv", lambda: polars_read(new))]
        for (_, w_order), (_, r_order) in zip(alternating(args.rounds, writers),
                                              alternating(args.rounds, readers)):
            for name, call in w_order + r_order:
                times[name].append(_timed(call))
        same = np.array_equal(Results.from_csv(old).table(), polars_read(new), equal_nan=True)
        print(f"sizes: savetxt {old.stat().st_size / 1e6:.1f} MB, polars "
              f"{new.stat().st_size / 1e6:.1f} MB; same values: {same}")
    med = {name: statistics.median(t) for name, t in times.items()}
    for name, t in times.items():
        print(f"{name:20s} median {med[name]:6.3f} s  fastest {min(t):6.3f} s  "
              f"({', '.join(f'{x:.3f}' for x in t)})")
    print(f"write: polars / savetxt {med['to_csv (polars)'] / med['savetxt %.17g']:.3f}; "
          f"read: polars / loadtxt {med['polars.read_csv'] / med['from_csv (loadtxt)']:.3f}")


if __name__ == "__main__":
    main()
