"""The command line's option values read into what the facade functions take: a metric
window ``t0:t1``, ``--set Component.variable=value`` overrides, a ``--filters`` list, the
``--train-seeds`` list, the text of ``--version``, a YAML configuration file."""
from __future__ import annotations

import math
from pathlib import Path

from ..errors import NavfmuError

#: where a command writes when no --out is given (a folder per scenario below it)
DEFAULT_OUT = Path("navfmu-results")


def nonempty_path(ctx, param, value):
    """click callback: a path option or argument given as empty text is refused (it would
    otherwise read as "not given" and write to the default place)."""
    if value is not None and not str(value).strip():
        import click

        raise click.BadParameter("empty path; give a file or folder name", ctx, param)
    return value


def nonempty_name(ctx, param, value):
    """click callback: a name option given as empty text is refused (it would otherwise read
    as "not given" and run the default)."""
    if value is not None and not str(value).strip():
        import click

        raise click.BadParameter("empty name", ctx, param)
    return value


def version_text() -> str:
    """``navfmu 0.1.0 (FMI 2.0 FMUs; Python 3.x.y)``: navfmu's version (its one definition,
    ``navcore.__version__``), the FMI standard of its FMUs and the running Python's."""
    import platform

    import navcore

    return (f"navfmu {navcore.__version__} (FMI {navcore.FMI_VERSION} FMUs; Python "
            f"{platform.python_version()})")


def _comma_list(option: str, text: str):
    """``a,b,c`` -> the stripped items; an empty list or an empty item (``Kf,``) is refused."""
    items = [f.strip() for f in str(text).split(",")]
    if not any(items):
        raise NavfmuError(f"{option}: empty list; give at least one")
    if not all(items):
        raise NavfmuError(f"{option}: an empty item in {text!r}; separate the items by single "
                          "commas")
    return items


def parse_train_seeds(text):
    """``--train-seeds 101,102`` -> ``[101, 102]``; not given (None) -> ``[]`` (the model's
    own seeds)."""
    if text is None:
        return []
    items = _comma_list("--train-seeds", text)
    try:
        return [int(s) for s in items]
    except ValueError:
        raise NavfmuError(f"--train-seeds: expected comma-separated integers, got "
                          f"{text!r}") from None


def filter_names(text):
    """``A,B,C`` -> names; at least one, none empty, none twice."""
    names = _comma_list("--filters", text)
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise NavfmuError(f"--filters: {', '.join(twice)} listed more than once ({text})")
    return names


def parse_window(text):
    """``t0:t1`` [s] -> ``(t0, t1)`` with ``t1 > t0``; empty -> None (the whole run)."""
    if not text:
        return None
    try:
        t0, t1 = (float(x) for x in text.split(":"))
    except ValueError:
        raise NavfmuError(f"--window: expected 't0:t1' in seconds, got {text!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise NavfmuError(f"--window: t0 and t1 must be finite numbers of seconds, got "
                          f"{text!r}")
    if not t1 > t0:
        raise NavfmuError(f"--window: t1 must be greater than t0, got {text!r}")
    return t0, t1


def _typed_value(value):
    """The text of a ``--set`` value as an int, float or bool where it reads as one."""
    for conv in (int, float):
        try:
            return conv(value)
        except ValueError:
            continue
    if value.lower() in ("true", "false"):
        return value.lower() == "true"
    return value


def parse_sets(items):
    """``Component.variable=value`` items -> ``{"Component.variable": value}``, the value an
    int, float or bool where it reads as one, else the text."""
    values = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or "." not in key:
            raise NavfmuError(f"--set: expected Component.variable=value, got {item!r}")
        values[key] = _typed_value(value)
    return values


def parse_named_sets(items):
    """``name=value`` items (one FMU's parameters) -> ``{"name": value}``, typed as by
    :func:`parse_sets`."""
    values = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise NavfmuError(f"--set: expected name=value, got {item!r}")
        values[key.strip()] = _typed_value(value)
    return values


__all__ = ["DEFAULT_OUT", "nonempty_path", "nonempty_name", "version_text", "filter_names",
           "parse_train_seeds", "parse_window", "parse_sets", "parse_named_sets",
           "read_yaml_mapping"]

def read_yaml_mapping(path, keys: str) -> dict:
    """A command's YAML configuration file as a mapping; a file that cannot be read, is not
    YAML or is not a mapping (of ``keys``, named in the error) is an error naming it."""
    import yaml

    path = Path(path)
    try:
        config = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise NavfmuError(f"{path}: cannot be read: {exc}") from None
    except yaml.YAMLError as exc:
        raise NavfmuError(f"{path}: not YAML: {str(exc).splitlines()[0]}") from None
    if not isinstance(config, dict):
        raise NavfmuError(f"{path}: expected a mapping of {keys}")
    return config
