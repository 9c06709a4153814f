"""The command line's conventions: ``-h`` wherever ``--help`` works, ``--version``, one default
per concept shown in the help, the names close to a mistyped one, ``--ssv`` binding parameter
sets in order under ``--set``, ``report --scenario`` choosing the scenarios, and ``tune``
printing how to apply its result."""
from __future__ import annotations

import platform
import re
import shutil

import click
import pytest

import navcore
from orchestrator.building import build as fmu_build
from orchestrator.campaigns.defaults import DEFAULT_RUNS, DEFAULT_SEED, DEFAULT_WORKERS
from orchestrator.cli.commands import cli, main
from orchestrator.model.ssp import load_ssd
from orchestrator.model.suggestions import close_matches, did_you_mean
from orchestrator.reporting.report import MODELS, scenario_folders
from orchestrator.running.ssv_bindings import overrides

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"


def _commands():
    ctx = click.Context(cli)
    found = [((), cli)]

    def walk(group, words):
        for name in group.list_commands(ctx):
            cmd = group.get_command(ctx, name)
            found.append((words + (name,), cmd))
            if isinstance(cmd, click.Group):
                walk(cmd, words + (name,))

    walk(cli, ())
    return found


COMMANDS = _commands()


def _navfmu(capsys, *args):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out, err = capsys.readouterr()
    return exc.value.code, out, err


@pytest.mark.parametrize("words", [w for w, _ in COMMANDS],
                         ids=[" ".join(w) or "navfmu" for w, _ in COMMANDS])
def test_dash_h_is_help(capsys, words):
    code_h, out_h, _ = _navfmu(capsys, *words, "-h")
    code_help, out_help, _ = _navfmu(capsys, *words, "--help")
    assert code_h == code_help == 0
    assert out_h == out_help and out_h.startswith("Usage: navfmu")


def test_version_names_navfmu_fmi_and_python(capsys):
    code, out, _ = _navfmu(capsys, "--version")
    assert code == 0
    assert out.strip() == (f"navfmu {navcore.__version__} (FMI {navcore.FMI_VERSION} FMUs; "
                           f"Python {platform.python_version()})")


def test_the_package_version_is_navcores():
    from importlib.metadata import PackageNotFoundError, version

    text = (fmu_build.ROOT / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in text and 'attr = "navcore.__version__"' in text
    try:
        assert version("navfmu") == navcore.__version__
    except PackageNotFoundError:
        pytest.skip("navfmu is not installed here")


def _unset(value) -> bool:
    """click's marker of an option without a default (8.2 and later; None before)."""
    return type(value).__name__ == "Sentinel" or repr(value).endswith("UNSET")


# option name -> the one default of its concept (bench --executors states its own)
SHARED = {"--workers": DEFAULT_WORKERS, "--seed": DEFAULT_SEED, "--runs": DEFAULT_RUNS}


@pytest.mark.parametrize("words,cmd", COMMANDS, ids=[" ".join(w) or "navfmu" for w, _ in COMMANDS])
def test_defaults_are_shown_and_shared(words, cmd):
    ctx = click.Context(cmd, info_name=" ".join(words), show_default=True)
    for param in cmd.params:
        if not isinstance(param, click.Option) or param.is_flag or param.multiple:
            continue
        name, default = param.opts[0], param.get_default(ctx, call=False)
        if default is not None and not _unset(default):   # shown (show_default everywhere)
            assert "[default:" in param.get_help_record(ctx)[1], name
        if name in SHARED and not _unset(default) and default is not None \
                and words != ("bench",):
            assert default == SHARED[name], (words, name)


def test_shared_defaults_are_the_library_defaults():
    import inspect

    from orchestrator.campaigns import campaign, executor, genetic, tune
    from orchestrator.reporting import report
    from orchestrator.verification import verify

    assert executor.Executor().workers == DEFAULT_WORKERS
    assert campaign.CampaignSpec("s", ("Kf",), 1).seed == DEFAULT_SEED
    assert genetic.GeneticAlgorithm(1).seed == DEFAULT_SEED
    for fn in (report.build_report, verify.verify, tune.run_tune, campaign.run_campaign):
        assert inspect.signature(fn).parameters["workers"].default == DEFAULT_WORKERS, fn
    assert inspect.signature(report.build_report).parameters["runs"].default == DEFAULT_RUNS


def test_close_matches_best_first_and_none_when_far():
    names = ["r_pos_n", "r_pos_e", "r_pos_d", "p0_pos", "init_lat"]
    assert close_matches("r_pos_nn", names)[0] == "r_pos_n"
    assert close_matches("R_POS_N", names)[0] == "r_pos_n"       # case ignored, name kept
    assert close_matches("zzzz", names) == [] and did_you_mean("zzzz", names) == ""
    assert did_you_mean("Iakff", ["Iakf", "Kf"]) == "; did you mean 'Iakf'?"


def test_mistyped_option_and_command_are_suggested(capsys):
    code, _, err = _navfmu(capsys, "run", str(MODEL), "--stp", "1")
    assert code == 2 and "Did you mean" in err and "'--stop'" in err.splitlines()[0]
    code, _, err = _navfmu(capsys, "rnu")
    assert code == 2 and err.splitlines()[0] == ("navfmu: error: No such command 'rnu'. Did "
                                                 "you mean 'run'?")


def _ssv(path, values):
    rows = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v}"/></ssv:Parameter>'
                   for k, v in values.items())
    path.write_text('<?xml version="1.0"?><ssv:ParameterSet version="1.0" name="p" '
                    'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">'
                    f"<ssv:Parameters>{rows}</ssv:Parameters></ssv:ParameterSet>")
    return path


def test_ssv_bindings_apply_in_order_under_set(tmp_path):
    model = load_ssd(MODEL)
    first = _ssv(tmp_path / "a.ssv", {"r_pos_n": 1.0, "r_pos_e": 2.0})
    second = _ssv(tmp_path / "b.ssv", {"filter.r_pos_e": 3.0, "gnss.pos_sigma_n": 4.0})
    values = overrides([f"filter={first}", str(second)], model, {"gnss.pos_sigma_n": 9.0})
    assert values == {"filter.r_pos_n": 1.0, "filter.r_pos_e": 3.0, "gnss.pos_sigma_n": 9.0}


def test_report_scenarios_chosen_in_order_each_once(tmp_path):
    every = scenario_folders(MODELS)
    assert [p.name for p in every] == sorted(p.name for p in every) and len(every) >= 5
    chosen = scenario_folders(MODELS, ["aircraft_outliers", "aircraft_500s", "aircraft_outliers"])
    assert [p.name for p in chosen] == ["aircraft_outliers", "aircraft_500s"]
    copy = tmp_path / "mine"
    shutil.copytree(MODEL, copy)
    assert scenario_folders(MODELS, [str(copy)]) == [copy]


def test_tune_prints_the_ssv_that_applies_its_result(capsys, tmp_path):
    fmu_build.build(log=None)
    out = tmp_path / "tuned"
    ahrs = fmu_build.ROOT / "models" / "ahrs_turntable"
    code, stdout, err = _navfmu(capsys, "tune", ahrs, "--params", "fuzzy_e_z_right",
                                "--generations", "1", "--population", "2", "--stop", "0.5",
                                "--out", out)
    assert code == 0, err
    last = stdout.strip().splitlines()[-1]
    assert last == f"apply it with: navfmu run {ahrs} --ssv filter={out}/filter_tuned.ssv"
    assert sorted(p.name for p in out.iterdir()) == ["filter_tuned.ssv", "fitness.png",
                                                      "tune.json"]
    tuned = re.search(r"filter\.fuzzy_e_z_right = (\S+)", stdout).group(1)
    bound = overrides([f"filter={out}/filter_tuned.ssv"], load_ssd(ahrs))
    assert bound["filter.fuzzy_e_z_right"] == float(tuned)
