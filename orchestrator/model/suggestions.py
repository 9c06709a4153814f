""""Did you mean": the names close to one a user mistyped (a parameter, a component, a filter,
a model folder), for the one error line that refuses it.

Closeness is :func:`difflib.get_close_matches`'s ratio (the standard library's; click uses it
for options too), so the suggestions read the same wherever a name is refused.
"""
from __future__ import annotations

import difflib
from typing import Iterable, List

#: at most this many names are suggested
MAX_SUGGESTIONS = 3
#: the least difflib ratio of a suggestion (difflib's default: 0.6)
CUTOFF = 0.6


def close_matches(name: str, candidates: Iterable[str]) -> List[str]:
    """The candidates closest to ``name``, best first (case ignored in the comparison)."""
    by_folded = {}
    for c in candidates:
        by_folded.setdefault(str(c).lower(), str(c))
    found = difflib.get_close_matches(str(name).lower(), list(by_folded), n=MAX_SUGGESTIONS,
                                      cutoff=CUTOFF)
    return [by_folded[f] for f in found]


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """``"; did you mean 'a' or 'b'?"`` for the names close to ``name``, else ``""``."""
    found = close_matches(name, candidates)
    if not found:
        return ""
    quoted = [f"'{f}'" for f in found]
    alternatives = quoted[0] if len(quoted) == 1 else (", ".join(quoted[:-1]) + " or "
                                                        + quoted[-1])
    return f"; did you mean {alternatives}?"


__all__ = ["close_matches", "did_you_mean", "MAX_SUGGESTIONS", "CUTOFF"]
