"""``docs/config.md``, generated from the declarations.

    python -m pairflock_env.config.docs docs/config.md     # rewrite the file
    python -m pairflock_env.config.docs                    # print it

``tests/test_config.py`` fails while the committed file differs from :func:`render`.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from pairflock_env.config.fields import Field, fmt_num
from pairflock_env.config.limits import LIMITS
from pairflock_env.config.model import SCHEMA
from pairflock_env.config.presets import PRESETS
from pairflock_env.config.schema import Schema
from pairflock_env.interfaces.pair_params import PAIR_INTERFACE_SCHEMA

__all__ = ["main", "render"]

_HEADER = """# Configuration reference

<!-- Generated from the declarations in pairflock_env/config/sections/ by
     `python -m pairflock_env.config.docs docs/config.md`; do not edit by hand
     (tests/test_config.py fails while this file is stale). -->

Every field of `PairFlockConfig` is a flat keyword of `make_config(preset, **overrides)`, of
`PairFlockConfig(...)`, of `cfg.replace(...)` and of every view (`parallel_env(n_uavs=50,
d_m=4)`, `gymnasium.make("pairflock/PairFlock-v0", dynamics="quadrotor")`, ...), and an
attribute (`cfg.n_uavs`). `cfg.section("flocking")` returns one section's values.

The defaults are the paper's values (Sec. VI-A, docs/paper-notes.md): the `paper` preset is
the defaults, and the column of every other preset (`paper-quadrotor`, `large`,
`crazyflie`) lists only what that preset changes. `dim` and `substeps` follow `dynamics`
unless set. An unknown keyword raises `TypeError` with a
did-you-mean hint; a wrong type `TypeError`; a value outside "valid" `ValueError`; each names
the field, the value and what is valid. The rules between fields and the derived quantities
below are checked at construction as well, so an accepted config runs: every step stays
finite and bounded in time and memory (the limits at the end). How to add a field: the
docstring of `pairflock_env.config`.
"""


def _num(x: Any) -> str:
    if isinstance(x, bool) or x is None or isinstance(x, str):
        return repr(x).replace("'", '"')
    if isinstance(x, (tuple, list)):
        inner = ", ".join(_num(v) for v in x)
        return f"({inner},)" if len(x) == 1 else f"({inner})"
    return fmt_num(x)


def _code(x: Any) -> str:
    return f"`{_num(x)}`"


def _text(s: str) -> str:
    return " ".join(s.split()).replace("|", "\\|")


def _table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def _default(f: Field) -> str:
    if f.auto is not None:
        return _text(f.auto.doc)
    return _code(f.default)


def _field_rows(
    fields: Iterable[Field], presets: Sequence[Mapping[str, Any]] = ()
) -> list[list[str]]:
    rows = []
    for f in fields:
        row = [f"`{f.name}`", f.kind.type_name, f.unit, _default(f)]
        row += [_code(pr[f.name]) if f.name in pr else "" for pr in presets]
        row += [_text(f.kind.valid()), _text(f.doc)]
        rows.append(row)
    return rows


def _sections(schema: Schema, presets: Mapping[str, Mapping[str, Any]]) -> list[str]:
    out: list[str] = []
    head = ["field", "type", "unit", "default (= paper)", *presets, "valid", "meaning"]
    for sec in schema.sections:
        out += ["", f"## {sec.title} (`{sec.name}`)", "", _text(sec.doc), ""]
        out += _table(head, _field_rows(sec.fields, tuple(presets.values())))
    return out


def _rules(schema: Schema) -> list[str]:
    out = ["", "## Rules between fields", ""]
    out += ["An error names the field you set among those a rule involves.", ""]
    rows = [[", ".join(f"`{n}`" for n in r.fields), _text(r.doc)] for r in schema.rules]
    out += _table(["fields", "rule"], rows)
    out += ["", "## Derived quantities", ""]
    out += ["Each must be finite and lie in the valid interval.", ""]
    rows = [
        [
            _text(d.name),
            _text(d.doc),
            d.unit,
            d.interval(),
            ", ".join(f"`{n}`" for n in d.fields),
        ]
        for d in schema.derived
    ]
    out += _table(["quantity", "formula", "unit", "valid", "fields"], rows)
    return out


def _limits() -> list[str]:
    out = ["", "## Limits", "", "The bounds above come from `pairflock_env.config.limits`:", ""]
    rows = [[f"`{lim.name}`", fmt_num(lim.value), lim.unit, _text(lim.why)] for lim in LIMITS]
    return out + _table(["limit", "value", "unit", "why"], rows)


def _frame_params() -> list[str]:
    sec = PAIR_INTERFACE_SCHEMA.sections[0]
    out = ["", f"## {sec.title} (`frame_params`)", "", _text(sec.doc), ""]
    head = ["parameter", "type", "unit", "default", "valid", "meaning"]
    return out + _table(head, _field_rows(sec.fields))


def render() -> str:
    """The whole of ``docs/config.md``."""
    lines = [_HEADER.rstrip("\n")]
    lines += _sections(SCHEMA, {k: v for k, v in PRESETS.items() if k != "paper"})
    lines += _rules(SCHEMA)
    lines += _limits()
    lines += _frame_params()
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Write :func:`render` to the path given (or print it)."""
    args = list(sys.argv[1:] if argv is None else argv)
    text = render()
    if not args:
        sys.stdout.write(text)
    else:
        Path(args[0]).write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
