"""`scalesynth stiffness MECH|CONFIG|RUN_DIR --pose=... [--design ...] [--load=...] [--set k=v ...]`: stiffness at
one pose."""

from __future__ import annotations

from typing import Annotated

import typer

from scalesynth.cliapp import (
    DesignOpt,
    JsonOpt,
    SetOpt,
    SourceArg,
    _design_inputs,
    _parse_vector,
    _print_json,
    app,
    handles_errors,
)
from scalesynth.errors import InvalidParameter


@app.command("stiffness")
@handles_errors
def stiffness_cmd(
    mechanism: SourceArg,
    pose: Annotated[str, typer.Option("--pose", help="task coordinates, comma-separated")],
    design_choice: DesignOpt = None,
    load: Annotated[str | None, typer.Option("--load", help="force on the platform, N: Fx,Fy(,Fz)")] = None,
    joints: Annotated[str, typer.Option("--joints", help="ideal (moment-free passive joints) or bonded (welded)")]
    = "ideal",
    sets: SetOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Deflection, compliance and stiffness of the platform at one pose (working mode = the kernel's), and the
    frame model solved (links, joints, actuators, platform, load) with every unit."""
    from scalesynth.mechanisms import available, get
    from scalesynth.stiffness.report import JOINT_MODELS, modelled, pose_stiffness

    mech, design, options = _design_inputs(mechanism, design_choice, sets)
    if joints in JOINT_MODELS and not modelled(mech):  # a bad --joints is named first (pose_stiffness)
        names = [n for n in available() if modelled(get(n))]
        raise InvalidParameter(f"mechanism: no stiffness model for {mech.name} yet (modelled: {', '.join(names)})")
    p = _parse_vector("--pose", pose, len(mech.task_axes))
    if load is not None:
        n = len(options["load"]) if "load" in options else 3
        options = mech.resolve_options({**options, "load": _parse_vector("--load", load, n)})
    out = pose_stiffness(mech, design, options, p, joints)
    if as_json:
        _print_json(out)
        return
    u = out["units"]["length"]
    units = {"length": u, "angle": "rad"}
    where = ", ".join(f"{a}={v:g} {units[t]}" for a, t, v in zip(mech.task_axes, mech.task_units, out["pose"],
                                                                     strict=True))
    typer.echo(f"{mech.name} at {where}, mode {out['branch']}, "
               f"{joints} joints, "
               f"load {out['load']} N")
    fmt = "{:.6g}".format

    def show(v):
        return v if isinstance(v, str) else fmt(v)

    typer.echo(f"  deflection ({u}): [{', '.join(show(v) for v in out['deflection'])}]  "
               f"|d| = {show(out['deflection_norm'])}{'  (singular pose)' if out['singular'] else ''}")
    typer.echo(f"  stiffness_min (N/{u}): {show(out['stiffness_min'])}")
    for key in ("compliance", "stiffness"):
        typer.echo(f"  {key} over ({', '.join(out['dofs'])}), {out['units'][key]}:")
        for row in out[key]:
            typer.echo("    [" + ", ".join(f"{show(v):>12}" for v in row) + "]")
    m = out["model"]
    typer.echo(f"  model: {len(m['links'])} links, {len(m['joints'])} joints, {len(m['actuators'])} actuators, "
               f"platform {m['platform']['body']} ({m['platform']['kind']}); --json prints it whole")
    for note in m.get("notes", []):
        typer.echo(f"  note: {note}")
