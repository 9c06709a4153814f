"""The sensor-log rules at their edges, on logs written out by hand: each bound taken at
exactly its value and just past it, the line an error names when blank lines are skipped, the
time origin of a log that starts just below a whole second, the text the writer gives a log
held relative to an origin, and how the folder is written (next to the destination, with the
permissions of a folder made by mkdir)."""
from __future__ import annotations

import numpy as np
import pytest

from navcore.sensors import sensorlog
from navcore.sensors.sensorlog import LogError, SensorLog, check_log, read_log, write_log


def _imu(times, dt):
    """IMU columns with zero increments at the given interval ends and lengths."""
    n = len(times)
    return {"time": np.array(times, dtype=float), "dt": np.array(dt, dtype=float),
            **{f"dtheta_{a}": np.zeros(n) for a in "xyz"},
            **{f"dvel_{a}": np.zeros(n) for a in "xyz"}}


def _gnss(times, lat=0.7):
    n = len(times)
    return {"time": np.array(times, dtype=float), "lat": np.full(n, lat),
            "lon": np.full(n, 2.0), "h": np.full(n, 100.0), "valid": np.ones(n)}


def _small_log():
    """Ten intervals of 0.01 s ending at 0.01 ... 0.1 s, fixes at 0.05 and 0.1 s."""
    return SensorLog(_imu(0.01 * np.arange(1, 11), [0.01] * 10), _gnss([0.05, 0.1]))


@pytest.mark.parametrize("missing", ["imu", "gnss"])
def test_a_log_without_imu_or_gnss_data_is_not_written(tmp_path, missing):
    """Both files are required (read_log refuses a folder without one): writing a log that
    lacks one is refused naming it, and nothing is written."""
    log = _small_log()
    setattr(log, missing, None)
    with pytest.raises(LogError) as exc:
        write_log(tmp_path / "log", log)
    assert str(exc.value).startswith(f"{tmp_path / 'log'}/{missing}.csv: no data"), exc.value
    assert not (tmp_path / "log").exists()
    with pytest.raises(LogError) as exc:
        check_log(log, sources={f"{missing}.csv": "/data/converted.txt"})
    assert str(exc.value).startswith("/data/converted.txt: no data"), exc.value


IMU_TITLES = ("time [s],dt [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dvel_x [m/s],"
              "dvel_y [m/s],dvel_z [m/s]")
GNSS_TITLES = "time [s],lat [rad],lon [rad],h [m],valid"


def _imu_line(time, dt="0.01"):
    return f"{time},{dt},0,0,0,0,0,0"


def _folder(tmp_path, imu_lines, gnss_lines=("0.02,0.7,2,100,1",), imu_titles=IMU_TITLES,
            gnss_titles=GNSS_TITLES):
    """A log folder written here line by line (not by write_log)."""
    folder = tmp_path / "log"
    folder.mkdir(parents=True)
    (folder / "imu.csv").write_text("\n".join([imu_titles, *imu_lines]) + "\n")
    (folder / "gnss.csv").write_text("\n".join([gnss_titles, *gnss_lines]) + "\n")
    return folder


THREE_INTERVALS = [_imu_line("0.01"), _imu_line("0.02"), _imu_line("0.03")]


@pytest.mark.parametrize("title,message", [
    ("dt [s", "unknown column 'dt [s'"),                 # no closing bracket: no unit
    ("dt]", "unknown column 'dt]'"),                      # a bracket without " ["
    ("dt [s [s]", "column 'dt' has the unit header 'dt [s [s]', expected 'dt [s]'"),
])
def test_a_title_is_split_at_its_first_space_bracket_only_when_it_ends_in_one(
        tmp_path, title, message):
    folder = _folder(tmp_path, THREE_INTERVALS, imu_titles=IMU_TITLES.replace("dt [s]", title))
    with pytest.raises(LogError) as exc:
        read_log(folder)
    assert str(exc.value).startswith(f"{folder / 'imu.csv'}, line 1: {message}"), exc.value


def test_a_file_of_exactly_the_size_limit_is_read(tmp_path, monkeypatch):
    folder = _folder(tmp_path, THREE_INTERVALS)
    size = (folder / "imu.csv").stat().st_size
    monkeypatch.setattr(sensorlog, "MAX_FILE_BYTES", size)
    assert read_log(folder).imu["time"].tolist() == [0.01, 0.02, 0.03]
    monkeypatch.setattr(sensorlog, "MAX_FILE_BYTES", size - 1)
    with pytest.raises(LogError, match=f"imu.csv: {size} bytes, more than the limit"):
        read_log(folder)


def test_files_are_read_as_utf8_whatever_the_locale(tmp_path, monkeypatch):
    """A title with a micro sign, in UTF-8, is named as written also where the locale's
    encoding is Latin-1 (simulated: ``open`` without an encoding reads Latin-1)."""
    import builtins

    def open_in_a_latin1_locale(file, mode="r", *args, encoding=None, **kwargs):
        return builtins.open(file, mode, *args, encoding=encoding or "latin-1", **kwargs)

    folder = _folder(tmp_path, THREE_INTERVALS, gnss_titles=GNSS_TITLES.replace("h [m]",
                                                                                "h [\u00b5m]"))
    monkeypatch.setattr(sensorlog, "open", open_in_a_latin1_locale, raising=False)
    with pytest.raises(LogError, match="column 'h' has the unit header 'h \\[\u00b5m\\]'"):
        read_log(folder)


@pytest.mark.parametrize("text,message", [
    ("", ", line 1: no column titles"),
    ("\n" + IMU_TITLES + "\n" + _imu_line("0.01") + "\n", ", line 1: no column titles"),
    (IMU_TITLES + "\n", ": no samples after the title line"),
], ids=["empty", "blank-first-line", "titles-only"])
def test_a_file_without_titles_or_samples_is_refused(tmp_path, text, message):
    folder = _folder(tmp_path, THREE_INTERVALS)
    (folder / "imu.csv").write_text(text)
    with pytest.raises(LogError) as exc:
        read_log(folder)
    assert str(exc.value) == f"{folder / 'imu.csv'}{message}"


def test_blank_lines_are_skipped_and_counted_in_the_line_an_error_names(tmp_path):
    lines = [_imu_line("0.01"), "", _imu_line("0.02"), "  ", _imu_line("0.03")]
    assert read_log(_folder(tmp_path / "a", lines)).imu["time"].tolist() == [0.01, 0.02, 0.03]
    # the file's lines: 1 titles, 2 0.01, 3 blank, 4 0.02, 5 blank, 6 0.02 again
    lines[4] = _imu_line("0.02")
    with pytest.raises(LogError, match=r"imu.csv, line 6: duplicated time 0.02 s \(line 4 "):
        read_log(_folder(tmp_path / "b", lines))
    fixes = ["0.01,0.7,2,100,1", "", "0.02,1.6,2,100,1"]
    with pytest.raises(LogError, match=r"gnss.csv, line 4: lat = 1.6 rad is not a latitude"):
        read_log(_folder(tmp_path / "c", THREE_INTERVALS, fixes))


def test_a_log_starting_below_a_whole_second_is_held_relative_to_that_second(tmp_path):
    """First interval end 1.995 s: the origin is 1 s (not the 2 s of the next line), every
    file's times are read minus 1 s, and writing adds it back to the exact text, the other
    values in %.17g (lower-case exponent)."""
    lines = [_imu_line("1.995"), "2.005,0.01,1e-05,0,0,0,0,0", _imu_line("2.015")]
    log = read_log(_folder(tmp_path, lines, ["2.0,0.7,2,100,1"]))
    assert log.time_origin == 1.0
    assert log.imu["time"].tolist() == [0.995, 1.005, 1.015]   # Decimal text minus 1, rounded
    assert log.gnss["time"].tolist() == [1.0]
    write_log(tmp_path / "again", log)
    imu = (tmp_path / "again" / "imu.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in imu[1:]] == ["1.995", "2.005", "2.015"]
    assert imu[2].split(",")[1:4] == ["0.01", "1.0000000000000001e-05", "0"]
    gnss = (tmp_path / "again" / "gnss.csv").read_text().splitlines()
    assert gnss[1].split(",")[:2] == ["2.0", "0.69999999999999996"]


@pytest.mark.parametrize("lines,line", [
    (["1e-99999999999999999999,0.01,0,0,0,0,0,0", _imu_line("0.02")], 2),
    ([_imu_line("1.995"), _imu_line("2.005"), "1e-99999999999999999999,0.01,0,0,0,0,0,0"], 4),
], ids=["first-line", "after-a-whole-second-origin"])
def test_a_time_that_float_reads_but_exact_decimal_text_cannot_is_refused(tmp_path, lines,
                                                                           line):
    """float() reads an exponent of 20 digits (as 0.0); the exact reading of times, which
    keeps UNIX stamps to the last digit, cannot: the error names file, line and column."""
    folder = _folder(tmp_path, lines)
    with pytest.raises(LogError) as exc:
        read_log(folder)
    assert str(exc.value).startswith(f"{folder / 'imu.csv'}, line {line}: column 'time': "
                                     "'1e-99999999999999999999' is not a number"), exc.value


def test_dt_must_be_positive_and_the_first_bad_line_is_named(tmp_path):
    log = _small_log()
    log.imu["dt"][3] = 0.0
    log.imu["dt"][6] = -0.01
    with pytest.raises(LogError) as exc:
        write_log(tmp_path / "log", log)
    assert str(exc.value).startswith(f"{tmp_path / 'log'}/imu.csv, line 5: dt = 0.0 s must "
                                     "be > 0"), exc.value


def test_reading_takes_the_jitter_bound_given(tmp_path):
    """One interval 1.5 times the nominal (a deviation of 0.5): within the default bound
    0.75, refused at 0.25."""
    times = [0.01, 0.02, 0.035, 0.045, 0.055]
    write_log(tmp_path / "log", SensorLog(_imu(times, [0.01, 0.01, 0.015, 0.01, 0.01]),
                                          _gnss([0.02])))
    assert read_log(tmp_path / "log").imu["dt"][2] == 0.015
    with pytest.raises(LogError, match=r"imu.csv, line 4: dt = 0.015 s is 1.5 times the "
                       r"nominal interval .* beyond max_dt_jitter = 0.25"):
        read_log(tmp_path / "log", max_dt_jitter=0.25)


def test_the_tiling_bound_is_a_millionth_of_dt(tmp_path):
    """Intervals of 0.5 s with a gap of exactly 5e-7 s (1e-6 dt, exact in binary) tile; a gap
    of 1e-6 s does not."""
    sensorlog.check_imu("imu.csv", _imu([-5e-7, 0.5], [0.5, 0.5]))
    with pytest.raises(LogError, match=r"imu.csv, line 3: gap of 1e-06 s"):
        sensorlog.check_imu("imu.csv", _imu([-1e-6, 0.5], [0.5, 0.5]))


@pytest.mark.parametrize("lat,line", [(0.5 * np.pi, 2), (1.6, 3), (-1.6, 3)])
def test_a_latitude_at_or_beyond_the_pole_is_refused(tmp_path, lat, line):
    log = _small_log()
    log.gnss = _gnss([0.02, 0.04, 0.06])
    log.gnss["lat"][line - 2:] = lat            # the first bad line and the next
    with pytest.raises(LogError, match=rf"gnss.csv, line {line}: lat = {lat!r} rad is not a "
                       "latitude"):
        check_log(log)


def test_truth_samples_exactly_the_bound_apart_are_accepted():
    log = _small_log()
    log.truth = {c: np.zeros(3) for c in sensorlog.TRUTH_COLUMNS}
    log.truth["time"] = np.array([0.0, 1.0, 2.0])
    check_log(log)
    log.truth["time"][2] = np.nextafter(2.0, 3.0)
    with pytest.raises(LogError, match=r"truth.csv, line 4: gap of 1 s after line 3"):
        check_log(log)


@pytest.mark.parametrize("fixes", [[-0.1, 0.0], [0.1, 0.2]], ids=["ending-at-start",
                                                                  "starting-at-stop"])
def test_fixes_touching_the_imu_span_at_one_end_overlap_it(fixes):
    """The IMU covers [0, 0.1] s: fixes that end at 0 or start at 0.1 share that instant."""
    check_log(SensorLog(_small_log().imu, _gnss(fixes)))
    shifted = np.array(fixes) + (-1e-9 if fixes[0] < 0 else 1e-9)
    with pytest.raises(LogError, match=r"gnss.csv: times .* do not overlap the IMU's"):
        check_log(SensorLog(_small_log().imu, _gnss(shifted)))


def test_errors_name_the_source_or_the_place_given():
    log = _small_log()
    log.gnss["valid"][:] = 0.0
    with pytest.raises(LogError) as exc:
        check_log(log)
    assert str(exc.value).startswith("sensor log/gnss.csv: no valid fix"), exc.value
    log = SensorLog(_small_log().imu, _gnss([5.0]))
    with pytest.raises(LogError) as exc:
        check_log(log, where="run", sources={"gnss.csv": "/data/fixes.txt"})
    assert str(exc.value).startswith("/data/fixes.txt: times 5.0 to 5.0 s do not overlap the "
                                     "IMU's 0.0 to 0.1 s (run/imu.csv)"), exc.value


@pytest.mark.parametrize("sizes", [(10, 9), (0, 0)], ids=["unequal", "empty"])
def test_columns_of_unequal_or_zero_length_are_refused(sizes):
    n, n_dt = sizes
    imu = _imu(0.01 * np.arange(1, n + 1), [0.01] * n_dt)
    with pytest.raises(LogError) as exc:
        check_log(SensorLog(imu, _gnss([0.05])))
    assert str(exc.value) == ("sensor log/imu.csv: columns of different or zero length "
                              f"{sorted({n, n_dt})}")


@pytest.mark.parametrize("value", [np.nan, None], ids=["nan", "none"])
def test_a_value_that_is_not_finite_is_named_with_line_and_column(value):
    """Also in a column no other rule reads (the height), and a missing value (None) of a
    column given as a list."""
    log = _small_log()
    log.gnss["h"] = [100.0, value]
    with pytest.raises(LogError) as exc:
        check_log(log)
    assert str(exc.value).startswith("sensor log/gnss.csv, line 3: column 'h' is nan (values "
                                     "must be finite)"), exc.value


def test_columns_of_numbers_as_text_are_written_as_their_values(tmp_path):
    """A column as a csv reader hands it (decimal texts) is written as the float64 numbers."""
    log = _small_log()
    log.gnss["h"] = ["100.5", "1e-05"]
    write_log(tmp_path / "log", log)
    rows = (tmp_path / "log" / "gnss.csv").read_text().splitlines()
    assert [row.split(",")[3] for row in rows] == ["h [m]", "100.5", "1.0000000000000001e-05"]


def test_the_log_is_written_in_a_hidden_folder_next_to_the_destination(tmp_path, monkeypatch):
    """While the files are written they are in '.<name>.<random>.tmp' beside the destination
    (a crash leaves a recognizable hidden folder, and the final move stays on one file
    system); folders above the destination are made."""
    written_in = []
    write_table = sensorlog._write_table

    def spy(path, data, origin=0.0):
        written_in.append(path.parent)
        write_table(path, data, origin)

    monkeypatch.setattr(sensorlog, "_write_table", spy)
    destination = tmp_path / "a" / "b" / "log"
    write_log(destination, _small_log())
    assert len(set(written_in)) == 1 and len(written_in) == 2
    temporary = written_in[0]
    assert temporary.parent == destination.parent
    assert temporary.name.startswith(".log.") and temporary.name.endswith(".tmp")
    assert len(temporary.name) > len(".log..tmp") and not temporary.exists()
    assert sorted(p.name for p in destination.iterdir()) == ["gnss.csv", "imu.csv"]


def test_a_new_log_folder_has_the_permissions_mkdir_gives(tmp_path):
    """The temporary folder (mode 0o700) becomes the log: it is given the mode a folder made
    by mkdir has under the same umask."""
    import os
    import stat
    os.mkdir(tmp_path / "made-by-mkdir")
    write_log(tmp_path / "log", _small_log())
    assert (stat.S_IMODE((tmp_path / "log").stat().st_mode)
            == stat.S_IMODE((tmp_path / "made-by-mkdir").stat().st_mode))
