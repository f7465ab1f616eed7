"""``scalesynth mobility MECH``: degrees of freedom and motion type of a mechanism (issue 4).

Two answers side by side (see ``scalesynth.mobility``): the Grübler-Kutzbach counts from the mechanism's
joint list (classical, and modified with the common/redundant constraints the paper or spec uses, named in the
output), and a screw-theory check: the rank of the constraint system at K random feasible configurations
(min, max and the generic value), the platform's dof and its motion type (3T, 2R1T, 3T3R, 2T, ...).
"""

from __future__ import annotations

from typing import Annotated

import typer

from scalesynth.cliapp import DesignOpt, JsonOpt, SetOpt, SourceArg, _design_inputs, _print_json, app, handles_errors
from scalesynth.errors import InvalidParameter

MAX_SAMPLES = 10_000  # each sample is a random feasible configuration and an SVD: 10 000 take about a minute


@app.command("mobility")
@handles_errors
def mobility_cmd(
    mechanism: SourceArg,
    design_choice: DesignOpt = None,
    sets: SetOpt = None,
    samples: Annotated[
        int, typer.Option("--samples", help="random feasible configurations for the screw-theory rank check")
    ] = 20,
    seed: Annotated[int, typer.Option("--seed", help="seed of the random configurations")] = 0,
    as_json: JsonOpt = False,
) -> None:
    """Mobility: G-K counts from the joint list, screw-theory rank at random feasible configurations."""
    from scalesynth.mobility import mobility_report

    if not 1 <= samples <= MAX_SAMPLES:
        raise InvalidParameter(f"--samples: expected an integer in [1, {MAX_SAMPLES}], got {samples}")
    mech, design, options = _design_inputs(mechanism, design_choice, sets)
    report = mobility_report(mech, design, options, samples=samples, seed=seed)
    out = report.to_dict()
    if as_json:
        _print_json(out)
        return
    for line in _text(mech, out):
        typer.echo(line)


def _text(mech, out: dict) -> list[str]:
    top, gk, num = out["topology"], out["grubler"], out["numeric"]
    d = top["order"]
    lines = [
        f"{mech.name} (seed {mech.seed}): {mech.title}; declared motion {out['expected_motion']}",
        "  chains: " + "; ".join(f"{label} = {' '.join(kinds)}" for label, kinds in top["chains"].items()),
        f"  n = {top['n_links']} links, g = {top['n_joints']} joints, sum f = {top['sum_freedom']}"
        + ("" if d == 6 else " (planar)"),
        f"  classical G-K  {gk['classical_formula']} = {gk['classical']}",
        f"  modified G-K   {gk['modified_formula']} = {gk['modified']}   uses: {gk['uses']}",
    ]
    if gk["note"]:
        lines.append(f"                 note: {gk['note']}")
    ex = gk.get("parallelograms_expanded")
    if ex:
        lines.append(
            f"  parallelograms as 4 R each: n = {ex['n_links']}, g = {ex['n_joints']}, "
            f"sum f = {ex['sum_freedom']}: classical {ex['classical']}, nu = {ex['nu']}, "
            f"modified {ex['modified']}"
        )
    rank, dof = num["constraint_rank"], num["dof"]
    lines += [
        f"  screw theory at {num['samples']} random feasible configurations: "
        f"constraint rank {rank['generic']} (min {rank['min']}, max {rank['max']}) "
        f"-> dof {dof['generic']}, motion {num['motion']}",
        f"                 constraints per chain {', '.join(map(str, num['chain_constraints']))}; "
        f"lambda = {num['lambda']} (in space {num['lambda_in_space']}), nu = {num['nu']}",
        f"  agrees (counts, screws, declared motion): {'yes' if out['agrees'] else 'NO'}",
    ]
    return lines
