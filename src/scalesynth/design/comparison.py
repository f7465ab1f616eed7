"""The comparison of ``scalesynth design``: per candidate mechanism its requirements (met, failed with the best
value seen, or not evaluated and why), its best designs, and the recommendation with its reasons.

Every number comes from a run's results (``pareto.csv``, ``population.csv``, the manifest); a requirement this
scalesynth cannot evaluate for a mechanism is reported as such (``"status": "not evaluated"``), never estimated.
Lengths are in the spec's unit.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from scalesynth import metrics
from scalesynth.cycle.config import METRES_PER_UNIT
from scalesynth.design.spec import DesignSpec

# the requirements and columns a comparison shows (the catalogue module keeps every metric name)
REQUIREMENTS = metrics.DESIGN_REQUIREMENTS
SHOWN = metrics.DESIGN_COLUMNS


def _num(v) -> float | None:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _why_not(req: str, spec: DesignSpec, cfg_data: dict[str, Any], notes: list[str], mech) -> str:
    """Why a requirement is not evaluated for a mechanism (a phrase)."""
    from scalesynth.metrics import catalogue

    cat = catalogue(mech)
    cycle_note = next((n for n in notes if n.startswith("cycle not evaluated")), None)
    if req == "cycle":
        return cycle_note or "no cycle"
    if req == "rate":
        if spec.motors is None:
            return "the spec names no motors (motors: catalogue, model, gear_ratio)"
        if "picks_per_minute" not in cat:
            return "this scalesynth has no motor model (no picks_per_minute in the metric catalogue)"
        return cycle_note or "no cycle"
    if req == "deflection":
        if spec.stiffness is None:
            return "the spec states no stiffness requirement"
        return f"{mech.name} has no per-voxel stiffness field yet (no task_max_deflection in its catalogue)"
    return "not evaluated"


def _requirement_values(spec: DesignSpec, unit: str) -> dict[str, float]:
    k = METRES_PER_UNIT[spec.units.length] / METRES_PER_UNIT[unit]
    out = {"envelope": 1.0, "cycle": 1.0, "rate": spec.cycle.picks_per_minute}
    if spec.stiffness is not None:
        out["deflection"] = spec.stiffness.max_deflection * k
    return out


def mechanism_entry(spec: DesignSpec, cand, result) -> dict[str, Any]:
    """The comparison entry of one candidate from its RunResult (None: its run failed)."""
    from scalesynth.metrics import catalogue
    from scalesynth.selection import choose

    mech = result.cfg.mech
    unit = cand.length_unit
    to_spec = METRES_PER_UNIT[unit] / METRES_PER_UNIT[spec.units.length]
    cat = catalogue(mech, unit)
    constrained = {c["metric"]: c for c in cand.config["constraints"]}
    targets = _requirement_values(spec, unit)
    pareto = result.pareto
    population = result.population
    nofeas = {e["constraint"]: e for e in result.manifest.get("no_feasible_design") or []}
    reqs: dict[str, Any] = {}
    for req, (metric, side, label) in REQUIREMENTS.items():
        if metric not in constrained:
            reqs[req] = {"label": label, "status": "not evaluated",
                         "why": _why_not(req, spec, cand.config, cand.notes, mech)}
            continue
        column = cat[metric].column
        bound = targets[req]
        scale = to_spec if cat[metric].unit == unit else 1.0  # lengths in the spec's unit
        if len(pareto):
            values = pareto[column].to_numpy(dtype=float)
            best = float(np.nanmax(values) if side == "min" else np.nanmin(values))
            reqs[req] = {"label": label, "status": "met", "needs": _needs(side, bound * scale),
                         "best": best * scale}
        else:
            seen = _num(nofeas.get(column, {}).get("best"))
            if seen is None and population is not None and column in population:
                vals = population[column].to_numpy(dtype=float)
                vals = vals[np.isfinite(vals)]
                seen = float(vals.max() if side == "min" else vals.min()) if len(vals) else None
            ok = seen is not None and (seen >= bound if side == "min" else seen <= bound)
            reqs[req] = {"label": label, "status": "met by some design" if ok else "failed",
                         "needs": _needs(side, bound * scale), "best": None if seen is None else seen * scale}
    designs = []
    if len(pareto):
        knee = choose(result.objective_matrix(), "knee")
        picks = {"knee": knee}
        for metric, sense in (("link_length_sum", "min"), ("task_gci", "max"), ("picks_per_minute", "max"),
                              ("task_max_deflection", "min")):
            if metric in cat and cat[metric].column in pareto:
                vals = pareto[cat[metric].column].to_numpy(dtype=float)
                if np.isfinite(vals).any():
                    picks[f"best-{metric}"] = int(np.nanargmin(vals) if sense == "min" else np.nanargmax(vals))
        for label, row in picks.items():
            designs.append(_design_row(label, row, pareto, result, cat, to_spec))
    failed = [r for r, v in reqs.items() if v["status"] == "failed"]
    return {
        "mechanism": mech.name,
        "title": getattr(mech, "title", mech.name),
        "length_unit": unit,
        "bounds": {k: list(v) for k, v in cand.bounds.items()},
        "sizing_rule": cand.rule,
        "notes": cand.notes,
        "run": str(result.out_dir),
        "feasible_designs": int(len(pareto)),
        "requirements": reqs,
        "can_do": bool(len(pareto)),
        "why_not": None if len(pareto) else (
            "; ".join(f"{reqs[r]['label']} failed: needs {reqs[r]['needs']}, best seen "
                      f"{_fmt(reqs[r]['best'])}" for r in failed)
            or "no design met every requirement together"),
        "designs": designs,
    }


def _needs(side: str, value: float) -> str:
    return f">= {value:.4g}" if side == "min" else f"<= {value:.4g}"


def _fmt(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def _design_row(label, row, pareto, result, cat, to_spec) -> dict[str, Any]:
    rec = pareto.iloc[row]
    design = result.design_of(rec)
    values = {}
    for metric, (_, length) in SHOWN.items():
        if metric in cat and cat[metric].column in pareto:
            v = _num(rec[cat[metric].column])
            values[metric] = None if v is None else (v * to_spec if length else v)
    return {"label": label, "row": int(row), "design": {k: float(v) for k, v in design.items()}, "values": values}


def _knee(entry) -> dict[str, Any] | None:
    return next((d for d in entry["designs"] if d["label"] == "knee"), None)


def recommend(entries: list[dict[str, Any]], spec: DesignSpec) -> dict[str, Any]:
    """The recommended mechanism and design, with reasons. Rule: among mechanisms with a design meeting every
    evaluated requirement, those with fewer requirements left unevaluated first (a design nobody checked for
    deflection is not preferred to one that was), then the smallest robot (link length sum of the knee design)."""
    able = [e for e in entries if e.get("can_do")]
    if not able:
        return {"mechanism": None, "design": None,
                "reasons": ["no candidate mechanism has a design meeting every evaluated requirement: "
                            + "; ".join(f"{e['mechanism']}: {e.get('why_not') or e.get('error')}" for e in entries)]}

    def unevaluated(e):
        return [r for r, v in e["requirements"].items() if v["status"] == "not evaluated"
                and not v["why"].startswith("the spec")]

    def key(e):
        return (len(unevaluated(e)), _knee(e)["values"].get("link_length_sum") or math.inf)

    ranked = sorted(able, key=key)
    best = ranked[0]
    knee = _knee(best)
    u = spec.units.length
    reasons = [f"{best['mechanism']}: its knee design meets every evaluated requirement with the smallest robot "
               f"(link length sum {_fmt(knee['values'].get('link_length_sum'))} {u}, task GCI "
               f"{_fmt(knee['values'].get('task_gci'))})"]
    reasons.append(_binding(best, knee, spec))
    missing = unevaluated(best)
    if missing:
        reasons.append("not evaluated for it: " + "; ".join(f"{best['requirements'][r]['label']} "
                                                              f"({best['requirements'][r]['why']})" for r in missing))
    if len(ranked) > 1:
        other = ranked[1]
        ok = _knee(other)
        a, b = knee["values"].get("link_length_sum"), ok["values"].get("link_length_sum")
        trade = (f"runner-up {other['mechanism']}: link length sum {_fmt(b)} {u}"
                 + (f" ({100 * (b / a - 1):+.0f} %)" if a and b else "")
                 + f", task GCI {_fmt(ok['values'].get('task_gci'))} against {_fmt(knee['values'].get('task_gci'))}")
        extra = unevaluated(other)
        if len(extra) != len(missing):
            trade += f"; {len(extra)} requirement(s) not evaluated for it against {len(missing)}"
        reasons.append(trade)
    for e in entries:
        if not e.get("can_do"):
            reasons.append(f"{e['mechanism']} cannot do the task: {e.get('why_not') or e.get('error')}")
    return {"mechanism": best["mechanism"], "design": knee, "reasons": reasons}


def _binding(entry, knee, spec: DesignSpec) -> str:
    """Which constraint binds at the chosen design: the evaluated requirement with the smallest relative margin
    (the envelope when only it is evaluated: a smaller robot would not reach the whole zone)."""
    vals = knee["values"]
    margins = []
    if spec.stiffness is not None and vals.get("task_max_deflection") is not None \
            and entry["requirements"]["deflection"]["status"] == "met":
        margins.append((1 - vals["task_max_deflection"] / spec.stiffness.max_deflection, "deflection",
                        f"{vals['task_max_deflection']:.3g} of {spec.stiffness.max_deflection:g} {spec.units.length}"))
    if vals.get("picks_per_minute") is not None and entry["requirements"]["rate"]["status"] == "met":
        margins.append((vals["picks_per_minute"] / spec.cycle.picks_per_minute - 1, "rate",
                        f"{vals['picks_per_minute']:.4g} of {spec.cycle.picks_per_minute:g} picks/min"))
    if not margins:
        return ("binding: the working zone (task coverage 1): the search shrinks the robot until it just reaches "
                "the whole zone")
    margin, what, text = min(margins)
    return f"binding: {what} ({text}, {100 * margin:.0f} % margin); the zone (task coverage 1) bounds the size"


def markdown(comparison: dict[str, Any]) -> str:
    """comparison.md."""
    spec_u = comparison["length_unit"]
    lines = [f"# Design comparison: {comparison['spec']}", ""]
    rec = comparison["recommendation"]
    lines.append(f"**Recommendation: {rec['mechanism'] or 'none'}**" + (
        f" (knee design, row {rec['design']['row']})" if rec["design"] else ""))
    lines += [""] + [f"- {r}" for r in rec["reasons"]] + [""]
    for e in comparison["mechanisms"]:
        lines += [f"## {e['mechanism']}", ""]
        if e.get("error"):
            lines += [f"run failed: {e['error']}", ""]
            continue
        lines.append(f"Bounds ({e['length_unit']}): " + ", ".join(
            f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in e["bounds"].items()) + f". Rule: {e['sizing_rule']}.")
        for n in e["notes"]:
            lines.append(f"Note: {n}.")
        lines += ["", "| requirement | status | needs | best |", "|---|---|---|---|"]
        for r in e["requirements"].values():
            lines.append(f"| {r['label']} | {r['status']} | {r.get('needs', '-')} | "
                         f"{_fmt(r.get('best')) if r['status'] != 'not evaluated' else r['why']} |")
        lines.append("")
        if not e["can_do"]:
            lines += [f"**Cannot do the task**: {e['why_not']}.", ""]
            continue
        cols = [m for m in SHOWN if any(d["values"].get(m) is not None for d in e["designs"])]
        lines.append("| design | " + " | ".join(SHOWN[c][0] + (f" {spec_u}" if SHOWN[c][1] else "")
                                                for c in cols) + " | parameters |")
        lines.append("|---" * (len(cols) + 2) + "|")
        for d in e["designs"]:
            lines.append(f"| {d['label']} | " + " | ".join(_fmt(d["values"].get(c)) for c in cols) + " | "
                         + ", ".join(f"{k} {v:.4g}" for k, v in d["design"].items()) + " |")
        lines.append("")
    if comparison["skipped"]:
        lines += ["## Not considered", ""] + [f"- {k}: {v}" for k, v in comparison["skipped"].items()] + [""]
    return "\n".join(lines)


def html(comparison: dict[str, Any], datasheet_link: str | None) -> str:
    """comparison.html: the markdown's tables as a self-contained page."""
    import html as h

    body = []
    for line in markdown(comparison).splitlines():
        if line.startswith("# "):
            body.append(f"<h1>{h.escape(line[2:])}</h1>")
        elif line.startswith("## "):
            body.append(f"<h2>{h.escape(line[3:])}</h2>")
        elif line.startswith("|---"):
            continue
        elif line.startswith("| "):
            cells = [c.strip() for c in line.strip("|").split("|")]
            body.append("<tr>" + "".join(f"<td>{h.escape(c)}</td>" for c in cells) + "</tr>")
        elif line.startswith("- "):
            body.append(f"<li>{h.escape(line[2:])}</li>")
        elif line:
            body.append(f"<p>{h.escape(line.replace('**', ''))}</p>")
    out, in_table, in_list = [], False, False
    for b in body:
        if b.startswith("<tr>") and not in_table:
            out.append("<table>")
            in_table = True
        if not b.startswith("<tr>") and in_table:
            out.append("</table>")
            in_table = False
        if b.startswith("<li>") and not in_list:
            out.append("<ul>")
            in_list = True
        if not b.startswith("<li>") and in_list:
            out.append("</ul>")
            in_list = False
        out.append(b)
    out.append("</table>" if in_table else "")
    out.append("</ul>" if in_list else "")
    link = f'<p><a href="{h.escape(datasheet_link)}">Datasheet of the recommended design</a></p>' \
        if datasheet_link else ""
    return ("<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>scalesynth design: "
            f"{h.escape(comparison['spec'])}</title><style>body{{font-family:sans-serif;max-width:1100px;margin:2em "
            "auto}}table{border-collapse:collapse;margin:1em 0}td{border:1px solid #ccc;padding:3px 8px;"
            "font-size:13px}tr:first-child td{font-weight:bold;background:#f0f0f0}</style></head><body>"
            + link + "\n".join(out) + "</body></html>")


def write(out: Path, comparison: dict[str, Any], datasheet_link: str | None) -> list[str]:
    from scalesynth import io as rio

    rio.write_json(out / "comparison.json", comparison)
    rio.write_text(out / "comparison.md", markdown(comparison))
    rio.write_text(out / "comparison.html", html(comparison, datasheet_link))
    return ["comparison.json", "comparison.md", "comparison.html"]
