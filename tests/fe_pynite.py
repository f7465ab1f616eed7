"""Rebuild a stiffness ``model`` (the JSON of `scalesynth stiffness --json`) as a PyNite frame and solve it.

PyNite (PyNiteFEA, a maintained 3-D frame finite-element package, test-only dependency) is the independent check
of scalesynth's solver: nothing here uses scalesynth code. Planar models live in the global XY plane with the
out-of-plane DOFs (DZ, RX, RY) held at every node. Joints: all parts meeting at a point share one node; a passive
revolute joint is a moment release (Rz) of the link end it names (the first part that is a link end when both
are), an actuator a rotational support spring at the base node (a slide along x or y to the base: a roller across
it and a support spring along it), a fixed joint no release. Rigid bodies (hinge plates, platform) are stars of
members 1e4 times stiffer than the stiffest link from the body's reference node.
"""

from __future__ import annotations

import numpy as np
from Pynite import FEModel3D

RIGID = 1e4  # penalty stiffness ratio: 1e4 balances penalty error against round-off (both ~1e-6 here)


def _key(p) -> tuple:
    return tuple(round(float(c), 7) for c in p)


def solve_model(model: dict, rigid: float = RIGID) -> np.ndarray:
    """Deflection (length unit) of the platform point under the model's load, by PyNite; ``rigid``: the penalty
    ratio of the rigid members (spatial models)."""
    if model["dim"] == 3:
        return solve_model_3d(model, rigid)
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
            if o == "base" and j["kind"] == "prismatic":  # a slide along a global axis: roller across it
                sup = supports.setdefault(n, {})
                sup[_across(j["axes"][0])] = sup["RZ"] = True  # a slide holds the carriage's rotation
            elif o == "base":
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
        along = "RZ" if a["kind"] == "revolute" else {"DX": "DY", "DY": "DX"}[_across(a["axis"])]
        fe.def_support_spring(n, along, a["stiffness"], None)
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


def _across(axis) -> str:
    """The global direction across a planar slide's axis, which must lie along x or y (PyNite's supports and
    support springs act along global axes)."""
    ax, ay = float(axis[0]), float(axis[1])
    assert min(abs(ax), abs(ay)) < 1e-12, f"planar slide along {axis}: only x or y slides are rebuilt"
    return "DY" if abs(ax) > abs(ay) else "DX"


AUX = 0.25  # length of an actuator's spring member (_fold_actuators), times the shortest link


def _fold_actuators(model: dict) -> tuple[dict[str, dict], list[dict]]:
    """Actuators that do not join two link ends (those are _merge_prismatic's), rebuilt exactly:

    * a prismatic actuator between a link end and a body or the base, the link along the sliding axis: the link's
      axial compliance adds the spring's, L/EA_eff = L/EA + 1/k (the joint passes every other force and moment and
      the link's axial force is constant), and the joint becomes a weld;
    * an actuator between a body and the base (prismatic or revolute), or a revolute one between a link end and
      the base: a spring member of length ell along the axis from a base node at ``at - ell axis`` to the joint
      point, axially (prismatic, EA = k ell) or torsionally (revolute, GJ = k ell) elastic and rigid in every
      other direction (its other rigidities are marked None and set to the rigid penalty), welded to the part.

    Returns the links by name and the joints."""
    links = {link["name"]: dict(link) for link in model["links"]}
    stiffness = {a["joint"]: a["stiffness"] for a in model["actuators"]}
    ell = AUX * min(link["length"] for link in model["links"])
    joints = []
    for j in (dict(j) for j in model["joints"]):
        ends = [p for p in j["parts"] if "." in p]
        if j["name"] not in stiffness or len(ends) == 2:
            joints.append(j)
            continue
        axis = np.asarray(j["axes"][0], dtype=float)
        k = stiffness[j["name"]]
        if ends and j["kind"] == "prismatic":
            name, end = ends[0].split(".")
            link = links[name]
            d = np.subtract(link["to"], link["from"])
            assert np.linalg.norm(np.cross(d, axis)) < 1e-9 * np.linalg.norm(d)
            assert np.allclose(link["from" if end == "a" else "to"], j["at"], atol=1e-9 * link["length"])
            link["EA"] = link["length"] / (link["length"] / link["EA"] + 1.0 / k)
            joints.append(dict(j, kind="fixed", axes=[]))
            continue
        body = next(p for p in j["parts"] if p != "base")  # a body or a link end
        assert "base" in j["parts"], "an actuator between two bodies: not needed yet"
        aux = f"act_{j['name']}"
        start = list(np.asarray(j["at"], dtype=float) - ell * axis)
        rot = j["kind"] == "revolute"
        links[aux] = {"name": aux, "from": start, "to": list(j["at"]), "length": ell, "EA": None if rot else k * ell,
                      "EIy": None, "EIz": None, "GJ": k * ell if rot else None}
        joints.append({"name": f"{aux}_base", "kind": "fixed", "at": start, "parts": [f"{aux}.a", "base"],
                       "axes": []})
        joints.append({"name": j["name"], "kind": "fixed", "at": j["at"], "parts": [f"{aux}.b", body], "axes": []})
    return links, joints


def _slide_stack(model: dict) -> tuple[dict, dict]:
    """Rigid bodies joined to the base and the platform only by prismatic joints at the platform's reference point
    (seed 000's PPaP chain): the platform's rotations are held rigidly, its translations along the passive slides are
    free and along an actuated slide a spring. Returns the model without them and the platform node's supports
    {"DX": True | False | stiffness, ..., "RX": True, ...}; the free, held and sprung directions must be global
    axes (PyNite's supports and support springs are)."""
    platform = model["platform"]["body"]
    bodies = {b["name"] for b in model["bodies"]} - {"base", platform}
    slides = [j for j in model["joints"] if j["kind"] == "prismatic" and all("." not in p for p in j["parts"])]
    stack, frontier = [], [platform]
    while frontier:  # the slides reachable from the platform through bodies
        body = frontier.pop()
        for j in slides:
            if body in j["parts"] and j not in stack:
                stack.append(j)
                frontier += [p for p in j["parts"] if p not in ("base", platform, body)]
    if not stack:
        return model, {}
    ref = np.asarray(model["platform"]["point"], dtype=float)
    stiffness = {a["joint"]: a["stiffness"] for a in model["actuators"]}
    used = {p for j in stack for p in j["parts"]} - {"base", platform}
    assert used <= bodies and not any(p in used for j in model["joints"] if j not in stack for p in j["parts"])
    assert all(np.allclose(j["at"], ref) for j in stack), "slides away from the platform's reference point"
    free = np.array([j["axes"][0] for j in stack if j["name"] not in stiffness]).reshape(-1, 3)
    supports = {"RX": True, "RY": True, "RZ": True}
    for d, axis in zip(("DX", "DY", "DZ"), np.eye(3), strict=True):
        sprung = [stiffness[j["name"]] for j in stack if j["name"] in stiffness and abs(abs(axis @ j["axes"][0]) - 1)
                  < 1e-12]
        in_free = free.size and np.linalg.matrix_rank(np.vstack([free, axis]), 1e-12) == np.linalg.matrix_rank(free)
        if in_free:
            supports[d] = False
        elif sprung:
            supports[d] = sprung[0]
        else:
            supports[d] = True
    assert np.linalg.matrix_rank(free) == sum(v is False for v in supports.values()), "slides not on global axes"
    rest = dict(model, joints=[j for j in model["joints"] if j not in stack],
                actuators=[a for a in model["actuators"] if a["joint"] not in {j["name"] for j in stack}],
                bodies=[b for b in model["bodies"] if b["name"] not in used])
    return rest, supports


def _merge_prismatic(model: dict) -> tuple[list[dict], list[dict]]:
    """Links joined end to end by a prismatic actuator (collinear, same section) become one member whose axial
    compliance adds the spring's: L/EA_eff = L_a/EA + 1/k + L_b/EA (the joint passes every other force and moment,
    and the axial force is the same along the leg). Other actuators: _fold_actuators. Returns the members and the
    remaining joints."""
    links, joints = _fold_actuators(model)
    stiffness = {a["joint"]: a["stiffness"] for a in model["actuators"]}
    for j in [j for j in joints if j["kind"] == "prismatic" and j["name"] in stiffness]:
        (na, ea), (nb, eb) = (p.split(".") for p in j["parts"])
        a, b = links.pop(na), links.pop(nb)
        assert (ea, eb) == ("b", "a") and (a["EIy"], a["EIz"], a["GJ"]) == (b["EIy"], b["EIz"], b["GJ"])
        axis = np.asarray(j["axes"][0])
        for link in (a, b):
            d = np.subtract(link["to"], link["from"])
            assert np.linalg.norm(np.cross(d, axis)) < 1e-9 * np.linalg.norm(d) * np.linalg.norm(axis)
        length = a["length"] + b["length"]
        comp = a["length"] / a["EA"] + b["length"] / b["EA"] + 1.0 / stiffness[j["name"]]
        name = f"{na}+{nb}"
        links[name] = dict(a, name=name, to=b["to"], length=length, EA=length / comp)
        rename = {f"{na}.a": f"{name}.a", f"{nb}.b": f"{name}.b"}
        joints = [dict(x, parts=[rename.get(p, p) for p in x["parts"]]) for x in joints if x["name"] != j["name"]]
    return list(links.values()), joints


def _distance(p, a, b) -> float:
    """Distance of point p from the segment a-b."""
    d = b - a
    t = 0.0 if not d @ d > 0 else min(1.0, max(0.0, float((p - a) @ d / (d @ d))))
    return float(np.linalg.norm(p - a - t * d))


def _oriented(fe, member: str, axis) -> None:
    """Rotate a member about its own axis so that its local z axis is ``axis`` (which must be normal to it). The
    angle is measured from PyNite's default orientation, so a second call (a member with a revolute at each end)
    must ask for the same axis."""
    m = fe.members[member]
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    if m.rotation != 0.0:
        assert abs(abs(a @ m.T()[2, :3]) - 1.0) < 1e-9, "two revolute releases about different axes on one member"
    m.rotation = 0.0
    dc = m.T()[:3, :3]  # rows: local x, y, z of the default orientation
    assert abs(a @ dc[0]) < 1e-9, "a revolute axis along a member cannot be a member end release"
    m.rotation = float(np.degrees(np.arctan2(-(a @ dc[1]), a @ dc[2])))


def solve_model_3d(model: dict, rigid: float = RIGID) -> np.ndarray:
    """Spatial models: every joint a member end release in the member's local axes (spherical: all rotations;
    revolute: the member turned so that local z is the axis, then Rz; universal: both bending rotations when both
    axes are normal to the member, else a rigid cross, see below); prismatic actuators merged into their leg
    (_merge_prismatic), other actuators as in _fold_actuators.

    A universal joint (orthogonal axes a1, a2) whose member is not normal to both axes is a rigid cross of two
    members, from the joint node X out to Q = X +- ell n (n = a1 x a2, the sign that keeps Q off every other member:
    PyNite would join it to a member it lies on) and back to a second node X' = X + 1e-6 ell a1
    (PyNite splits a member at every node on it, so X' must not coincide with X; the offset is normal to a2 and n so
    that both releases are about axes normal to their member): the first released about a1 at X, the second about
    a2 at X', the member starting at X'. Slide stacks (_slide_stack) become supports of the platform's node."""
    model, stack_supports = _slide_stack(model)
    links, joints = _merge_prismatic(model)
    fe = FEModel3D()
    nodes: dict[tuple, str] = {}

    def node(p) -> str:
        k = _key(p)
        if k not in nodes:
            nodes[k] = f"N{len(nodes)}"
            fe.add_node(nodes[k], *(float(c) for c in p))
        return nodes[k]

    E, G = 1.0, 1.0
    fe.add_material("mat", E, G, 0.3, 0.0)
    stiffest = max(max(link["EA"], link["EIy"], link["EIz"], link["GJ"]) for link in model["links"])
    welded = {p for j in joints if j["kind"] == "fixed" for p in j["parts"]}
    by_name = {link["name"]: link for link in links}

    def released_end(j) -> tuple[str, str]:
        """The member end a joint releases: one welded to nothing else at its node (the others share the node's
        rotations)."""
        ends = [p for p in j["parts"] if "." in p]
        free = [e for e in ends if e not in welded] or ends
        name, end = free[-1].split(".")
        return name, end

    bodies = {b["name"]: b for b in model["bodies"]}
    crosses, moved = [], {}  # universal joints rebuilt as crosses; (member, end) -> its node X'
    for j in joints:
        if j["kind"] != "universal":
            continue
        name, end = released_end(j)
        link = by_name[name]
        x = np.subtract(link["to"], link["from"]) / link["length"]
        if all(abs(np.dot(ax, x)) < 1e-9 for ax in j["axes"]):
            continue
        a1, a2 = (np.asarray(ax, dtype=float) for ax in j["axes"])
        assert abs(a1 @ a2) < 1e-9, "a universal joint's axes must be orthogonal"
        moved[(name, end)] = f"X{len(crosses)}"
        offset = 1e-6 * AUX * min(link["length"] for link in model["links"]) * a1
        fe.add_node(moved[(name, end)], *(float(c) for c in np.asarray(j["at"], dtype=float) + offset))
        crosses.append((j, a1, a2, moved[(name, end)]))
    for link in links:
        ea, eiy, eiz, gj = (rigid * stiffest if link[k] is None else link[k] for k in ("EA", "EIy", "EIz", "GJ"))
        fe.add_section(link["name"], ea / E, eiy / E, eiz / E, gj / G)
        start = moved.get((link["name"], "a")) or node(link["from"])
        fe.add_member(link["name"], start, moved.get((link["name"], "b")) or node(link["to"]), "mat", link["name"])
    fe.add_section("rigid", rigid * stiffest, rigid * stiffest, rigid * stiffest, rigid * stiffest)
    releases = {link["name"]: [False] * 12 for link in links}
    supported, held = set(), set()
    ell = AUX * min(link["length"] for link in model["links"])
    segments = [(np.asarray(link["from"], float), np.asarray(link["to"], float)) for link in links]
    segments += [(np.asarray(bodies[p]["ref"], float), np.asarray(j["at"], float)) for j in joints for p in j["parts"]
                 if p in bodies and p != "base"]
    for i, (j, a1, a2, x2) in enumerate(crosses):
        tips = [np.asarray(j["at"], dtype=float) + sign * ell * np.cross(a1, a2) for sign in (1.0, -1.0)]
        q = node(max(tips, key=lambda t: min(_distance(t, a, b) for a, b in segments)))
        for m, (ni, nj), ax, off in ((f"cross{i}_1", (node(j["at"]), q), a1, 5), (f"cross{i}_2", (q, x2), a2, 11)):
            fe.add_member(m, ni, nj, "mat", "rigid")
            _oriented(fe, m, ax)
            fe.def_releases(m, *[k == off for k in range(12)])
        held.update((node(j["at"]), q, x2))
    body_points: dict[str, set] = {}
    for j in joints:
        n = node(j["at"])
        for o in (p for p in j["parts"] if "." not in p):
            if o == "base":
                supported.add(n)
            else:
                body_points.setdefault(o, set()).add(_key(j["at"]))
        if j["kind"] == "fixed" or any(j is c[0] for c in crosses):
            continue
        assert j["name"] not in {a["joint"] for a in model["actuators"]}, "actuated revolute joints: not needed yet"
        name, end = released_end(j)
        off = 0 if end == "a" else 6
        if j["kind"] == "spherical":
            releases[name][off + 3 : off + 6] = [True, True, True]
        elif j["kind"] == "revolute":
            _oriented(fe, name, j["axes"][0])
            releases[name][off + 5] = True
        elif j["kind"] == "universal":
            m = fe.members[name]
            x = m.T()[0, :3]
            for ax in j["axes"]:
                assert abs(np.dot(ax, x)) < 1e-9, "universal joint axes must be normal to the member"
            releases[name][off + 4 : off + 6] = [True, True]
    for b, pts in body_points.items():
        ref = _key(bodies[b]["ref"])
        node(bodies[b]["ref"])
        for i, p in enumerate(sorted(pts)):
            if p != ref:
                fe.add_member(f"{b}_{i}", nodes[ref], nodes[p], "mat", "rigid")
                held.update((nodes[ref], nodes[p]))
    for link in links:
        fe.def_releases(link["name"], *releases[link["name"]])
        for p, off in ((link["from"], 0), (link["to"], 6)):
            if not all(releases[link["name"]][off + 3 : off + 6]):
                held.add(node(p))
    p = node(model["platform"]["point"])
    for n in nodes.values():
        free_rot = n not in held  # no member holds its rotations: support them (they carry nothing)
        fixed = [n in supported] * 3 + [n in supported or free_rot] * 3
        if n == p and stack_supports:
            fixed = [stack_supports[d] is True for d in ("DX", "DY", "DZ", "RX", "RY", "RZ")]
            for d in ("DX", "DY", "DZ"):
                if stack_supports[d] not in (True, False):
                    fe.def_support_spring(n, d, float(stack_supports[d]), None)
        fe.def_support(n, *fixed)
    for d, f in zip(("FX", "FY", "FZ"), model["load"]["force"], strict=True):
        fe.add_node_load(p, d, float(f))
    fe.analyze_linear(check_stability=False)
    nd = fe.nodes[p]
    return np.array([nd.DX["Combo 1"], nd.DY["Combo 1"], nd.DZ["Combo 1"]])
