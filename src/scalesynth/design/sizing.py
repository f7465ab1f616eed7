"""Candidates, bounds and run configs of ``scalesynth design``: which mechanisms can do a spec's task, where its
working zone lies in each mechanism's frame, sensible search bounds scaled from the zone, and the run config (the
schema users write, so ``scalesynth optimize`` reruns it).

Each sizing rule states its ranges as multiples of the zone's half-width ``a`` (radius of the circle holding the
zone's horizontal section) and its far depth ``D`` (base plane to the zone's far face), in the mechanism's own
length unit. Mechanisms without a rule get every length parameter scaled from its default design (stated as such).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from scalesynth.cycle.config import ADEPT_ACROSS_MM, METRES_PER_UNIT
from scalesynth.design.spec import DesignSpec

# the side of the base plane each mechanism works on (z, or y for planar ones): -1 below (hanging robots), +1 above
WORKING_SIDE = {"delta": -1, "linear-delta": -1, "planar-fivebar": -1, "2pauu-ppap": +1}


@dataclass
class Zone:
    """The working zone in one mechanism's frame and length unit: the task box per axis, the zone's centre on its
    near face, its half-width ``a``, height ``h``, far depth ``D`` and the side it lies on."""

    box: dict[str, tuple[float, float]]
    centre: list[float]
    a: float
    h: float
    D: float
    side: int
    path: list[list[float]] | None = None


@dataclass
class Candidate:
    """One mechanism's part of a design run: its config (JSON data) and the bounds it searched, with the rule."""

    mechanism: str
    config: dict[str, Any]
    bounds: dict[str, tuple[float, float]]
    rule: str
    length_unit: str
    notes: list[str] = field(default_factory=list)


def can_do(mech, spec: DesignSpec) -> str | None:
    """Why ``mech`` cannot do the spec's task (a phrase), or None."""
    if spec.envelope.form == "task":
        axes = tuple(spec.envelope.task.get("box") or {})
        if set(axes) != set(mech.task_axes):
            return f"its task axes are {', '.join(mech.task_axes)}; the task's are {', '.join(axes)}"
        return None
    if spec.envelope.planar:
        if mech.motion != "2T" or tuple(mech.task_axes) != ("x", "y"):
            return f"a planar zone is for planar 2T mechanisms (x, y); {mech.name} is {mech.motion}"
        return None
    if mech.motion != "3T" or tuple(mech.task_axes) != ("x", "y", "z"):
        return (f"a 3-D zone needs three translations x, y, z and nothing else; {mech.name} moves "
                f"{mech.motion} ({', '.join(mech.task_axes)})")
    return None


def candidates(spec: DesignSpec) -> tuple[list[str], dict[str, str]]:
    """(mechanisms to run, {mechanism: why not} for the registered ones left out or unable)."""
    from scalesynth.mechanisms import available, get

    names = spec.mechanisms or available()
    run, skipped = [], {}
    for name in names:
        mech = get(name)
        twin_of = getattr(getattr(mech, "description", None), "reproduces", None)
        if spec.mechanisms is None and twin_of in names:
            skipped[name] = f"the same robot as {twin_of} (its description); name it under mechanisms to run it too"
            continue
        why = can_do(mech, spec)
        if why is None:
            run.append(name)
        else:
            skipped[name] = why
    return run, skipped


def zone_in(mech, spec: DesignSpec, unit: str) -> Zone:
    """The spec's zone in ``mech``'s frame and length ``unit``."""
    k = METRES_PER_UNIT[spec.units.length] / METRES_PER_UNIT[unit]
    env = spec.envelope
    side = WORKING_SIDE.get(mech.name, -1)
    if env.form == "task":
        box = {ax: (lo * k, hi * k) for ax, (lo, hi) in env.task["box"].items()}
        axes = list(mech.task_axes)
        lo = [box[ax][0] for ax in axes]
        hi = [box[ax][1] for ax in axes]
        vert = axes[-1]
        near = box[vert][1] if box[vert][1] <= 0 else box[vert][0]
        side = -1 if box[vert][1] <= 0 else +1
        centre = [0.5 * (a + b) for a, b in zip(lo[:-1], hi[:-1], strict=True)] + [near]
        a = 0.5 * math.hypot(*[h - l for l, h in zip(lo[:-1], hi[:-1], strict=True)])
        h = hi[-1] - lo[-1]
        D = max(abs(lo[-1]), abs(hi[-1]))
        path = [[c * k for c in p] for p in env.task["path"]] if env.task.get("path") else None
        return Zone(box, centre, a, h, D, side, path)
    depth = env.depth * k
    if env.box is not None:
        wx, wy, h = env.box.x * k, env.box.y * k, env.box.z * k
        if env.planar:  # planar zone: x across, y vertical
            h = wy
            a = 0.5 * wx
            near = side * depth
            far = side * (depth + h)
            box = {"x": (-0.5 * wx, 0.5 * wx), "y": (min(near, far), max(near, far))}
            return Zone(box, [0.0, near], a, h, depth + h, side)
        a = 0.5 * math.hypot(wx, wy)
    else:
        wx = wy = env.cylinder.diameter * k  # the cylinder is checked through its bounding box (conservative)
        h = env.cylinder.height * k
        a = 0.5 * env.cylinder.diameter * k
    near, far = side * depth, side * (depth + h)
    box = {"x": (-0.5 * wx, 0.5 * wx), "y": (-0.5 * wy, 0.5 * wy), "z": (min(near, far), max(near, far))}
    return Zone(box, [0.0, 0.0, near], a, h, depth + h, side)


def _rule(name: str, z: Zone, mech) -> tuple[dict[str, tuple[float, float]], dict[str, float], dict[str, Any], str]:
    """(bounds, fixed design values, options, the rule in words) of a mechanism's sizing rule."""
    a, D = z.a, z.D
    if name == "delta":
        p = 0.2 * a
        return ({"base_radius": (p + 0.2 * a, p + 1.5 * a), "upper_arm": (0.5 * a, 3.0 * a),
                 "forearm": (max(1.0 * a, 0.5 * D), 4.0 * a + D)}, {"platform_radius": p}, {},
                "platform_radius = 0.2 a (fixed: only base_radius - platform_radius matters); base_radius - "
                "platform_radius in [0.2 a, 1.5 a]; upper_arm in [0.5 a, 3 a]; forearm in [max(a, D/2), 4 a + D]")
    if name == "linear-delta":
        p = 0.2 * a
        return ({"base_radius": (p + 0.6 * a, p + 2.5 * a), "forearm": (0.8 * a, 3.0 * a + 0.5 * D)},
                {"platform_radius": p}, {"stroke": [0.0, D]},
                "platform_radius = 0.2 a (fixed); base_radius - platform_radius in [0.6 a, 2.5 a]; forearm in "
                "[0.8 a, 3 a + D/2]; carriage stroke [0, D] below the base plane")
    if name == "planar-fivebar":
        return ({"r": (0.1 * a, 0.8 * a), "l1": (0.5 * a, max(1.6 * a, 0.6 * D)),
                 "l2": (max(1.0 * a, 0.5 * D), max(2.8 * a, 1.5 * D))}, {}, {},
                "r in [0.1 a, 0.8 a]; l1 in [0.5 a, max(1.6 a, 0.6 D)]; l2 in [max(a, D/2), max(2.8 a, 1.5 D)] "
                "(the five-bar example's ranges for its 1000 mm packing rectangle, scaled)")
    if name == "2pauu-ppap":
        s = max(a, 0.5 * D)
        return ({"m": (0.5 * s, 1.5 * s), "n": (0.2 * s, 1.0 * s), "l1": (0.5 * s, 1.5 * s + 0.5 * D),
                 "l2": (0.5 * s, 1.5 * s + 0.5 * D), "c": (0.1 * s, 0.5 * s)}, {}, {},
                "the paper's section 6.2 ranges (m, n, l1, l2, c) scaled by s = max(a, D/2) per metre, l1 and l2 "
                "extended by D/2 to reach the zone")
    # generic: every positive parameter scaled from the default design by the zone's size over the default's
    default = mech.resolve_design({})
    size = None
    for dm in mech.design_metrics:
        if dm.name == "footprint_radius":
            size = float(dm.value(default, mech.resolve_options({})))
    scale = a / size if size and size > 0 else 1.0
    bounds = {p.name: (0.5 * default[p.name] * scale, 2.0 * default[p.name] * scale)
              for p in mech.parameters if p.positive and default.get(p.name, 0) > 0}
    return (bounds, {}, {}, f"no sizing rule for {name}: every length parameter in [0.5, 2] x its default x "
            f"{scale:.3g} (the zone's half-width over the default design's footprint radius)")


def _cycle(spec: DesignSpec, z: Zone, mech, unit: str) -> dict[str, Any]:
    """The run config's cycle section: the adept cycle through the zone's centre, along x, at the zone's far
    face (picks at the bottom), or the spec's path placed at the zone's near face centre."""
    k = METRES_PER_UNIT[spec.units.length] / METRES_PER_UNIT[unit]
    cyc = spec.cycle
    base: dict[str, Any] = {"law": cyc.law, "cycles_per_minute": cyc.picks_per_minute, "payload": spec.rated_payload,
                            "samples": spec.search.cycle_samples}
    n = len(mech.task_axes)
    far = z.centre[-1] + z.side * z.h
    bottom = min(z.centre[-1], far)
    if cyc.path is not None:
        base["path"] = [[c * k + o for c, o in zip(p, z.centre, strict=True)] for p in cyc.path]
    else:
        across = ADEPT_ACROSS_MM * 0.001 / METRES_PER_UNIT[unit]
        start = [0.0] * n
        start[0] = -0.5 * across
        start[-1] = bottom
        base.update(preset="adept", start=start, direction=[1.0] + [0.0] * (n - 1))
    return base


def _supports(section: str) -> bool:
    from scalesynth.config import RunConfig

    return section in RunConfig.model_fields


def build(name: str, spec: DesignSpec) -> Candidate:
    """The run config (JSON data) of one candidate mechanism, with its bounds and rule."""
    from scalesynth.cycle.config import CycleConfig
    from scalesynth.mechanisms import get
    from scalesynth.metrics import catalogue

    mech = get(name)
    unit = mech.default_length_unit
    z = zone_in(mech, spec, unit)
    bounds, fixed, options, rule = _rule(name, z, mech)
    notes: list[str] = []
    cat = catalogue(mech, unit)
    design = {**mech.resolve_design({}), **fixed}
    for key, (lo, hi) in bounds.items():
        design[key] = 0.5 * (lo + hi)
    cycle = _cycle(spec, z, mech, unit)
    if spec.cycle.dwell_s and "dwell_s" in CycleConfig.model_fields:
        cycle["dwell_s"] = spec.cycle.dwell_s
    elif spec.cycle.dwell_s:
        notes.append("cycle.dwell_s: this scalesynth's cycle has no dwell; the rate is for motion only")
    constraints: list[dict[str, Any]] = [{"metric": "task_coverage", "min": 1.0},
                                        {"metric": "cycle_feasible", "min": 1.0}]
    data: dict[str, Any] = {"name": f"{spec.name}-{name}", "mechanism": name, "units": {"length": unit},
                            "design": design, "options": options}
    if spec.links is not None:
        _apply_links(spec, mech, unit, options, data, notes)
    if spec.stiffness is not None and "task_max_deflection" in cat and "load" in mech.option_names:
        k = METRES_PER_UNIT[spec.units.length] / METRES_PER_UNIT[unit]
        load = [0.0] * len(mech.task_axes)
        load[-1] = -spec.stiffness.force
        options["load"] = load
        for need in cat["task_max_deflection"].needs:  # switches the stiffness model needs (e.g. stiffness_metrics)
            if need.startswith("options.") and mech.resolve_options({}).get(need[8:]) is False:
                options[need[8:]] = True
        constraints.append({"metric": "task_max_deflection", "max": spec.stiffness.max_deflection * k})
    if spec.motors is not None and "picks_per_minute" in cat and _supports("motors"):
        data["motors"] = dict(spec.motors)
        constraints.append({"metric": "picks_per_minute", "min": spec.cycle.picks_per_minute})
    data.update({
        "bounds": {k: [float(lo), float(hi)] for k, (lo, hi) in bounds.items()},
        "grid": {"tolerance": {"volume": 0.01, "gci": 0.002}},
        "task": {"box": {ax: [float(lo), float(hi)] for ax, (lo, hi) in z.box.items()},
                 "resolution": spec.search.task_resolution, **({"path": z.path} if z.path else {})},
        "cycle": cycle,
        "objectives": [{"metric": "link_length_sum", "sense": "min"}, {"metric": "task_gci", "sense": "max"}],
        "constraints": constraints,
        "algorithm": {"name": "nsga2", "pop_size": spec.search.population, "n_gen": spec.search.generations,
                      "seed": spec.search.seed},
        "output": {"checkpoint_every": max(1, spec.search.generations)},
    })
    _drop_unsupported_cycle(data, notes)
    return Candidate(name, data, bounds, rule, unit, notes)


CYCLE_METRICS = ("cycle_feasible", "picks_per_minute")


def _drop_unsupported_cycle(data: dict[str, Any], notes: list[str]) -> None:
    """Leave out the cycle (and the motors, which act along it) where this mechanism cannot run one yet (e.g. no
    link geometry), saying why in ``notes``: its rate and utilisation are then not evaluated, never guessed."""
    from scalesynth.config import config_from_dict
    from scalesynth.errors import ConfigError

    try:
        config_from_dict(data)
    except ConfigError as err:
        text = str(err)
        if not text.startswith(("cycle", "motors", "dynamics")):
            raise
        data.pop("cycle", None)
        data.pop("motors", None)
        data["constraints"] = [c for c in data["constraints"] if c["metric"] not in CYCLE_METRICS]
        notes.append(f"cycle not evaluated: {text}")


def _apply_links(spec, mech, unit: str, options: dict[str, Any], data: dict[str, Any], notes: list[str]) -> None:
    """The spec's links (tube in the spec's unit, Young's modulus, density) into a candidate's options (its unit)
    and its dynamics' density; a mechanism without a tube option keeps its own sections, said in a note."""
    links = spec.links
    k = METRES_PER_UNIT[spec.units.length] / METRES_PER_UNIT[unit]
    for key, value in (("tube", None if links.tube is None else [v * k for v in links.tube]),
                       ("youngs_modulus", links.youngs_modulus)):
        if value is None:
            continue
        if key in mech.option_names:
            options[key] = value
        else:
            notes.append(f"links.{key}: {mech.name} has no such option; its own links are used")
    if links.density is not None:
        data["dynamics"] = {"density": float(links.density)}
