"""Rebuild a stiffness ``model`` (the JSON of `scalesynth stiffness --json`) as a PyNite frame and solve it.

PyNite (PyNiteFEA, a maintained 3-D frame finite-element package, test-only dependency) is the independent check
of scalesynth's solver: nothing here uses scalesynth code. Planar models live in the global XY plane with the
out-of-plane DOFs (DZ, RX, RY) held at every node. Joints: all parts meeting at a point share one node; a passive
revolute joint is a moment release (Rz) of the link end it names (the first part that is a link end when both
are), an actuator a rotational support spring at the base node, a fixed joint no release. Rigid bodies (hinge
plates, platform) are stars of members 1e4 times stiffer than the stiffest link from the body's reference node.
"""

from __future__ import annotations

import numpy as np
from Pynite import FEModel3D

RIGID = 1e4  # penalty stiffness ratio: 1e4 balances penalty error against round-off (both ~1e-6 here)


def _key(p) -> tuple:
    return tuple(round(float(c), 7) for c in p)


def solve_model(model: dict) -> np.ndarray:
    """Deflection (length unit) of the platform point under the model's load, by PyNite."""
    if model["dim"] != 2:
        raise NotImplementedError("planar models only")
    fe = FEModel3D()
    nodes: dict[tuple, str] = {}

    def node(p) -> str:
        k = _key(p)
        if k not in nodes:
            nodes[k] = f"N{len(nodes)}"
            fe.add_node(nodes[k], float(p[0]), float(p[1]), 0.0)
        return nodes[k]

    E = 1.0  # sections carry E: A = EA / E etc.
    fe.add_material("mat", E, 0.4, 0.3, 0.0)
    stiffest = 0.0
    for link in model["links"]:
        fe.add_section(link["name"], link["EA"] / E, link["EI"] / E, link["EI"] / E, 2 * link["EI"] / E)
        fe.add_member(link["name"], node(link["from"]), node(link["to"]), "mat", link["name"])
        stiffest = max(stiffest, link["EA"], link["EI"])
    fe.add_section("rigid", RIGID * stiffest, RIGID * stiffest, RIGID * stiffest, RIGID * stiffest)
    bodies = {b["name"]: b for b in model["bodies"]}
    releases: dict[str, list[bool]] = {link["name"]: [False] * 12 for link in model["links"]}
    keeps_rotation: dict[str, bool] = {}  # node -> some unreleased member or support holds its rotation
    supports: dict[str, dict] = {}
    body_points: dict[str, set] = {}
    for j in model["joints"]:
        n = node(j["at"])
        parts = j["parts"]
        links_here = [p for p in parts if "." in p]
        others = [p for p in parts if "." not in p]
        for o in others:
            if o == "base":
                sup = supports.setdefault(n, {"DX": True, "DY": True})
                if j["kind"] == "revolute" and j["name"] not in {a["joint"] for a in model["actuators"]}:
                    sup["RZ"] = True  # the released member does not need it; holds the node's spare DOF
                elif j["kind"] == "fixed":
                    sup["RZ"] = True
            elif bodies[o]["kind"] == "rigid":
                body_points.setdefault(o, set()).add(_key(j["at"]))
        if j["kind"] == "revolute" and j["name"] not in {a["joint"] for a in model["actuators"]}:
            name, end = links_here[-1].split(".") if len(links_here) == 2 else links_here[0].split(".")
            releases[name][5 if end == "a" else 11] = True
    for a in model["actuators"]:
        n = node(a["at"])
        fe.def_support_spring(n, "RZ", a["stiffness"], None)
    for b, pts in body_points.items():
        ref = _key(bodies[b]["ref"])
        node(bodies[b]["ref"])
        for i, p in enumerate(sorted(pts)):
            if p != ref:
                fe.add_member(f"{b}_{i}", nodes[ref], nodes[p], "mat", "rigid")
                keeps_rotation[nodes[ref]] = keeps_rotation[nodes[p]] = True
    for link in model["links"]:
        fe.def_releases(link["name"], *releases[link["name"]])
        for end, idx in ((link["from"], 5), (link["to"], 11)):
            if not releases[link["name"]][idx]:
                keeps_rotation[node(end)] = True
    for n in nodes.values():
        sup = supports.get(n, {})
        fe.def_support(n, sup.get("DX", False), sup.get("DY", False), True, True, True,
                       sup.get("RZ", False) or not keeps_rotation.get(n, False))
    p = node(model["platform"]["point"])
    fx, fy = model["load"]["force"]
    fe.add_node_load(p, "FX", fx)
    fe.add_node_load(p, "FY", fy)
    fe.analyze_linear(check_stability=False)
    nd = fe.nodes[p]
    return np.array([nd.DX["Combo 1"], nd.DY["Combo 1"]])
