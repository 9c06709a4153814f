"""The parameter-scale sweep's table (orchestrator.campaigns.sweep) on hand-made task results: means
over the seeds, ratios to the first filter, phase columns in the scenario's window order."""
from orchestrator.campaigns import sweep


def _point(pos, vel, att, nis=None):
    return {"rms_3d": {"position": pos, "velocity": vel, "attitude": att},
            "phases": {} if nis is None else {"nis": {"strong": nis[0], "low": nis[1]}}}


def test_table_means_over_seeds_and_ratios_to_the_baseline():
    results = {(0.5, "A", 0): _point(2.0, 0.2, 0.1, (6.0, 3.0)),
               (0.5, "A", 1): _point(4.0, 0.4, 0.3, (8.0, 3.0)),
               (0.5, "B", 0): _point(1.0, 0.1, 0.4, (3.0, 3.0)),
               (0.5, "B", 1): _point(2.0, 0.2, 0.4, (3.0, 2.0))}
    lines = sweep.sweep_table(results, ("A", "B"), ("nis",)).splitlines()
    assert lines[0].split(" | ")[-2:] == ["nis strong", "nis low |"]
    a = [c.strip() for c in lines[2].strip("|").split("|")]
    b = [c.strip() for c in lines[3].strip("|").split("|")]
    assert a == ["0.5", "A", "3.000", "0.3000", "0.2000", "1.00", "1.00", "1.00", "7", "3"]
    assert b == ["0.5", "B", "1.500", "0.1500", "0.4000", "0.50", "0.50", "2.00", "3", "2.5"]
