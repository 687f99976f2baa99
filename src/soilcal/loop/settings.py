"""Settings of the measured-data loop: a soil's optional ``loop`` block, checked by field
(the keys and defaults are listed in :mod:`soilcal.loop.core`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from soilcal.errors import InputError
from soilcal.loop.effects import EFFECTS, get


@dataclass
class Settings:
    alpha: float = 0.05
    effects: list = field(default_factory=lambda: list(EFFECTS))
    candidates: str = "matched"
    bounds: dict = field(default_factory=dict)
    reference: dict = field(default_factory=dict)
    design_points: int = 5
    fold_by: str | None = None
    max_effects: int = 2
    bootstrap: int = 200
    surrogate: str = "pooled"

    def effect_bounds(self, name: str) -> dict:
        return get(name).bounds(self.bounds.get(name))


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _bound(source, where: str, eff, k: str, v) -> list[float]:
    """One ``[low, high]`` of ``loop.bounds``: finite numbers, low < high, inside the
    parameter's physical range where the library states one (:attr:`Effect.ranges`)."""
    if k not in eff.params:
        raise InputError(source, where, "a parameter of the effect (" + ", ".join(eff.params) + ")", k)
    if not (isinstance(v, (list, tuple)) and len(v) == 2 and all(_number(x) for x in v)):
        raise InputError(source, where, "[low, high], two numbers", v)
    if not all(math.isfinite(x) for x in v):
        raise InputError(source, where, "[low, high], two finite numbers", v)
    if not v[0] < v[1]:
        raise InputError(source, where, "[low, high] with low < high", v)
    if k in eff.ranges:
        lo, hi = eff.ranges[k]
        if v[0] < lo or v[1] > hi:
            raise InputError(source, where, f"[low, high] within [{lo:g}, {hi:g}], the physical range of "
                             f"{k} of {eff.name}", v)
    return [float(v[0]), float(v[1])]


def settings_from(soil_data: dict, source="<soil>") -> Settings:
    """Settings of a soil's ``loop`` block, checked by field."""
    block = dict(soil_data.get("loop") or {})
    s = Settings()
    known = {f for f in asdict(s)}
    for k in block:
        if k not in known:
            raise InputError(source, f"loop.{k}", "one of " + ", ".join(sorted(known)), k)
    if "alpha" in block:
        a = block["alpha"]
        if not isinstance(a, (int, float)) or not 0 < a < 1:
            raise InputError(source, "loop.alpha", "a number in (0, 1)", a)
        s.alpha = float(a)
    if "effects" in block:
        if not isinstance(block["effects"] or [], list):
            raise InputError(source, "loop.effects", "a list of effects of the library (" + ", ".join(EFFECTS) + ")",
                             block["effects"])
        seen = set()
        for j, name in enumerate(block["effects"] or []):
            if name not in EFFECTS:
                raise InputError(source, f"loop.effects[{j}]", "one of " + ", ".join(EFFECTS), name)
            if name in seen:
                first = block["effects"].index(name)
                raise InputError(source, f"loop.effects[{j}]", f"each effect named once ({name} is loop.effects[{first}])",
                                 name)
            seen.add(name)
        s.effects = list(block["effects"] or [])
    if "candidates" in block:
        if block["candidates"] not in ("matched", "all"):
            raise InputError(source, "loop.candidates", "matched or all", block["candidates"])
        s.candidates = block["candidates"]
    bounds = block.get("bounds") or {}
    if not isinstance(bounds, dict):
        raise InputError(source, "loop.bounds", "a mapping effect -> parameter -> [low, high]", bounds)
    for name, b in bounds.items():
        eff = EFFECTS.get(name)
        if eff is None:
            raise InputError(source, f"loop.bounds.{name}", "an effect of the library (" + ", ".join(EFFECTS) + ")", name)
        if not isinstance(b, dict):
            raise InputError(source, f"loop.bounds.{name}", "a mapping parameter -> [low, high] (e.g. "
                             + ", ".join(f"{k}: [{lo:g}, {hi:g}]" for k, (_, (lo, hi)) in eff.params.items()) + ")", b)
        s.bounds[name] = {k: _bound(source, f"loop.bounds.{name}.{k}", eff, k, v) for k, v in b.items()}
    from soilcal.config.quantities import QUANTITIES

    for q, v in (block.get("reference") or {}).items():
        if q not in QUANTITIES or QUANTITIES[q] is None:
            raise InputError(source, f"loop.reference.{q}", "a numeric quantity ("
                             + ", ".join(k for k, u in QUANTITIES.items() if u) + ")", q)
        from soilcal.config.quantities import NONNEGATIVE_QUANTITIES, POSITIVE_QUANTITIES

        sign = "positive " if q in POSITIVE_QUANTITIES else "non-negative " if q in NONNEGATIVE_QUANTITIES else ""
        if (not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v)
                or (q in POSITIVE_QUANTITIES and not v > 0) or (q in NONNEGATIVE_QUANTITIES and v < 0)):
            raise InputError(source, f"loop.reference.{q}", f"a {sign}number in {QUANTITIES[q][0]}", v)
        s.reference[q] = float(v)
    if "design_points" in block:
        v = block["design_points"]
        if not isinstance(v, int) or v < 3:
            raise InputError(source, "loop.design_points", "an integer >= 3", v)
        s.design_points = v
    if "fold_by" in block:
        s.fold_by = block["fold_by"]
    if "bootstrap" in block:
        v = block["bootstrap"]
        if not isinstance(v, int) or isinstance(v, bool) or not (v == 0 or v >= 50):
            raise InputError(source, "loop.bootstrap", "0 (the fit's own interval) or an integer >= 50", v)
        s.bootstrap = v
    if "surrogate" in block:
        if block["surrogate"] not in ("pooled", "rows"):
            raise InputError(source, "loop.surrogate", "pooled or rows", block["surrogate"])
        s.surrogate = block["surrogate"]
    if "max_effects" in block:
        v = block["max_effects"]
        if not isinstance(v, int) or v < 1:
            raise InputError(source, "loop.max_effects", "an integer >= 1", v)
        s.max_effects = v
    return s
