"""Suggestions for a mistyped name ("did you mean ...?"), for errors that name what is there."""

from __future__ import annotations

import difflib
from collections.abc import Sequence

CUTOFF = 0.6  # difflib's default: close enough to be a typo or a missing package prefix


def did_you_mean(name: str, candidates: Sequence[str], limit: int = 3) -> str:
    """'; did you mean A or B?' when some of `candidates` are close to `name`, else the list of
    them all ('; there are: A, B, C'); '' when there are none. Dotted names are compared by
    their last part (a shared package would make every name look close; `Status` and
    `my.pkgg.Status` both find `my.pkg.Status`)."""
    if not candidates:
        return ""
    by_last_part: dict[str, list[str]] = {}
    for candidate in candidates:
        by_last_part.setdefault(candidate.rsplit(".", 1)[-1], []).append(candidate)
    lasts = difflib.get_close_matches(
        name.rsplit(".", 1)[-1], list(by_last_part), n=limit, cutoff=CUTOFF
    )
    close = [candidate for last in lasts for candidate in by_last_part[last]][:limit]
    if close:
        return f"; did you mean {' or '.join(close)}?"
    return f"; there are: {', '.join(candidates)}"
