"""Names that stored data still uses: the one place that reads what older releases wrote.

The package keeps no deprecated names in its API (docs/changes.md lists what was renamed
before the first release). Files written by earlier versions, the committed policies among
them, still hold a few old keys: a model's stored environment config may say
``safe_distance`` for ``reward_separation_distance``, its learning interface
``safe_distance`` for ``separation_distance``, and its training settings ``frame`` /
``frame_params`` for ``interface`` / ``interface_params``. Whatever loads such a mapping
passes it through :func:`upgrade_stored` first; nothing else maps old names.

    >>> upgrade_stored("interface", {"name": "pair", "safe_distance": 2.0})
    {'name': 'pair', 'separation_distance': 2.0}
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["STORED_RENAMES", "upgrade_stored"]

#: kind of stored mapping -> {old key: current key}. These keys are deprecated: they are
#: read from files, never accepted as keywords.
STORED_RENAMES: dict[str, dict[str, str]] = {
    "config": {"safe_distance": "reward_separation_distance"},
    "interface": {"safe_distance": "separation_distance"},
    "settings": {"frame": "interface", "frame_params": "interface_params"},
}


def upgrade_stored(kind: str, data: Mapping[str, Any]) -> dict[str, Any]:
    """``data`` (a stored mapping of kind ``kind``) with its old keys renamed.

    Raises ``ValueError`` for an unknown kind and when a mapping holds an old key and its
    current name both (the file is then ambiguous)."""
    if kind not in STORED_RENAMES:
        raise ValueError(f"kind={kind!r} is invalid: must be one of {sorted(STORED_RENAMES)}")
    if not isinstance(data, Mapping):
        raise TypeError(f"data={data!r} is invalid: must be a mapping")
    renames = STORED_RENAMES[kind]
    out: dict[str, Any] = {}
    for key, value in data.items():
        new = renames.get(key, key)
        if new != key and new in data:
            raise ValueError(f"stored {kind} holds both {key!r} and its current name {new!r}")
        out[new] = value
    return out
