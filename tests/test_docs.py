"""The signal tables in docs/ are generated from the declarations; keep them current."""
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_signal_tables_are_current():
    spec = importlib.util.spec_from_file_location("make_signal_tables",
                                                  ROOT / "docs" / "make_signal_tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert (ROOT / "docs" / "signals.md").read_text() == module.render(), \
        "docs/signals.md is stale: run python docs/make_signal_tables.py"
