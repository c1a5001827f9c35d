"""The certificate's page: one self-contained HTML document from a :class:`string.Template` skeleton
(:data:`PAGE`) whose sections are filled by small functions, one per section, from a
:class:`~ftcal.reporting._certificate.CalibrationCertificate`. Inline styles, pictures as data URIs, no script, no
network; it prints to a multi-page A4 PDF (the summary on the first page, page numbers, tables not cut)."""

from __future__ import annotations

import html
from pathlib import Path
from string import Template
from typing import Any

import numpy as np

from ._budget import BUDGET_MODEL
from ._calibration_report import CONDITION_FIELDS

__all__ = ["PAGE", "render_page", "CASES_ON_PAGE"]

#: Rows of the applied-vs-indicated table printed on the page (the worst; all are in the JSON and CSV).
CASES_ON_PAGE = 30
#: Readings dropped or flagged listed on the page (all are in the JSON).
READINGS_ON_PAGE = 40

#: The page's skeleton, ``certificate_page.html`` beside this module (its style sheet inline): every ``$name`` is
#: one section's HTML (:func:`render_page`).
PAGE = Template((Path(__file__).parent / "certificate_page.html").read_text(encoding="utf-8"))


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return html.escape(str(value))


def _table(head: list[str], rows: list[list[str]], classes: list[str] | None = None, long: bool = False) -> str:
    kinds = (["long"] if long else []) + (["kv"] if head == ["", ""] else [])
    cls_table = f' class="{" ".join(kinds)}"' if kinds else ""
    out = [f"<table{cls_table}><thead><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr></thead><tbody>"]
    for i, row in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes and classes[i] else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _not_stated(value: Any, how: str = "") -> str:
    if value is None:
        return f'<span class="not-stated">not stated</span>{(" — " + how) if how else ""}'
    return _fmt(value)


def _dof(value) -> str:
    return "∞" if value is None or not np.isfinite(value) else f"{value:.0f}" if value >= 10 else f"{value:.1f}"


# ------------------------------------------------------------------------------------------------- first page
def _summary(c) -> str:
    m, d, acc, cond = c.identity["model"], c.data, c.accuracy, c.conditions
    groups = (f", {_fmt(d['groups'])} groups" + (" (named by their files)" if d.get("group_names") else "")
              if d.get("groups") else "")
    parts = [
        f"<p class=\"note\">Issued {_fmt(c.identity['date_utc'])} by ftcal {_fmt(c.identity['ftcal_version'])}. Every "
        "accuracy figure is <b>held out</b>: errors on data the fitted calibration did not see.</p>",
        _table(["", ""], [
            ["sensor", _fmt(c.sensor)],
            ["model", f"{_fmt(m['type'])}" + (f" (chose {_fmt(m['chosen'])})" if m.get("chosen") else "")
             + (f", file <code>{_fmt(m['file'])}</code>" if m.get("file") else "")],
            ["date of issue", _fmt(c.identity["date_utc"])],
            ["data", f"{_fmt(d['rows'])} rows, {_fmt(d['channels'])} channels{groups}"
             + (f", <code>{_fmt(Path(d['file']).name)}</code>" if d.get("file") else "")],
            ["full scale", _fmt(c.full_scale_source)],
            ["specification", "none given (a spec of e.g. 1 % FS gives a PASS/FAIL per axis)" if c.spec_pct_fs is None
             else "U95 ≤ " + ", ".join(f"{a['axis']} {_fmt(a['spec_pct_fs'])} %" for a in acc) + " of full scale"],
            ["reference standard", _not_stated(cond.get("reference_standard"))],
            ["recalibration due", _not_stated(cond.get("recalibration_due"), "give a recalibration interval")]]),
        _verdict(c), _table(
            ["axis", "full scale", "U95", "k", "U95 [% FS]", "spec [% FS]", "result", "max error [% FS]"],
            [[a["axis"], f"{_fmt(a['full_scale'])} {a['unit']}", f"{_fmt(a['u95'])} {a['unit']}",
              _fmt(a["coverage_factor"]), _fmt(a["u95_pct_fs"]), _fmt(a.get("spec_pct_fs")),
              "–" if a.get("verdict") is None else f'<span class="{a["verdict"]}">{a["verdict"]}</span>',
              _fmt(a["max_pct_fs"])] for a in acc]),
        _budget_table(c),
        f"<p><b>Against the stock models:</b> {_fmt(c.comparison.get('sentence'))}</p>", _warnings(c)]
    return "\n".join(parts)


def _verdict(c) -> str:
    if c.verdict is None:
        return '<p class="verdict none">No specification given: no PASS/FAIL verdict.</p>'
    failed = [a["axis"] for a in c.accuracy if a["verdict"] == "FAIL"]
    return (f'<p class="verdict {c.verdict}">{c.verdict}: ' + (
        "every axis within its specification (expanded uncertainty U95)." if c.verdict == "PASS" else
        f"{', '.join(failed)} beyond the specification (expanded uncertainty U95).") + "</p>")


def _budget_table(c) -> str:
    """The uncertainty budget: one row per axis, one column per component (standard uncertainties)."""
    names = list(dict.fromkeys(x.name for b in c.budget for x in b.components))  # each component once, in order
    units = {a["name"]: a["unit"] for a in c.axes}
    rows = []
    for b in c.budget:
        comp = {x.name: x for x in b.components}
        rows.append([f"{b.axis} [{units[b.axis]}]"] + [
            "–" if n not in comp else "0" if comp[n].standard_uncertainty == 0 else
            f"{_fmt(comp[n].standard_uncertainty)} <span class=\"note\">({_dof(comp[n].dof)})</span>" for n in names]
            + [_fmt(b.combined_standard_uncertainty), _dof(b.effective_dof), _fmt(b.coverage_factor),
               _fmt(b.expanded_uncertainty)])
    return ("<h3>Uncertainty budget (standard uncertainties, degrees of freedom in brackets)</h3>"
            + _table(["axis"] + [_fmt(n) for n in names] + ["u<sub>c</sub>", "ν<sub>eff</sub>", "k", "U95"], rows)
            + "<p class=\"note\">GUM (JCGM 100), EURAMET cg-4: uncorrelated components, u<sub>c</sub> their root "
            "sum of squares; the held-out error is split into reproducibility and repeatability (nothing counted "
            "twice); k the t-factor at 95.45 % for the Welch-Satterthwaite ν<sub>eff</sub>; U95 = k·u<sub>c</sub>. "
            "The model and the source of each component: under <i>Held-out accuracy per axis</i>.</p>")


def _budget_sources(c) -> str:
    """The budget's model and where each component of the first axis comes from (the others alike)."""
    if not c.budget:
        return ""
    sources = "".join(f"<li><i>{_fmt(x.name)}</i>: {_fmt(x.source)}</li>" for x in c.budget[0].components)
    return (f"<h3>The uncertainty budget's model</h3><p class=\"note\">{_fmt(BUDGET_MODEL)}</p>"
            f"<p class=\"note\">Sources ({_fmt(c.budget[0].axis)}; the other axes alike):</p>"
            f"<ul class=\"note\">{sources}</ul>")


def _warnings(c) -> str:
    if not c.warnings:
        return "<h3>Warnings</h3><p>None.</p>"
    return "<h3>Warnings</h3><ul class=\"warnings\">" + "".join(
        f'<li><span class="warn-kind">{_fmt(w["kind"])}:</span> {_fmt(w["text"])}</li>' for w in c.warnings) + "</ul>"


# ------------------------------------------------------------------------------------------------ the calibration
def _calibration(c) -> str:
    m, d = c.identity["model"], c.data
    names = [a["name"] for a in c.axes]
    ident = [["model type", _fmt(m["type"])], ["model file", _not_stated(m.get("file"))],
             ["model SHA-256", f"<code>{_fmt(m['sha256'])}</code>"],
             ["load it (Python)", f"<code>ftcal.load_model({_fmt(repr(m.get('file') or 'MODEL.model.npz'))})</code>"],
             ["use it (command line)", f"<code>ftcal predict {_fmt(m.get('file') or 'MODEL.model.npz')} "
                                       "readings.csv</code>"]]
    if m.get("alpha") is not None:  # only a calibration of forces and torques scales its torques
        ident.append(["torque scale alpha (whole-wrench RMSE)", f"{_fmt(m['alpha'])} 1/m"])
    ident += [["data file", _not_stated(d.get("file"))], ["data SHA-256", f"<code>{_fmt(d.get('sha256'))}</code>"]]
    parts = [_table(["", ""], ident), _matrix(m.get("matrix"))]
    has_force, has_torque = any(a["unit"] == "N" for a in c.axes), any(a["unit"] != "N" for a in c.axes)
    kinds = ", ".join([k for k, has in (("forces in N", has_force),
                                         ("torques in N·m about the sensor frame's origin", has_torque)) if has])
    over = "<code>[F, alpha·T]</code> in N" if has_force and has_torque else "the axes above, in their unit"
    parts.append("<h3>Frames and units</h3><p>Outputs are <code>[" + ", ".join(names) + "]</code> in the <b>sensor "
                 f"frame</b>: {kinds}. Raw channels (" + ", ".join(_fmt(n) for n in d.get("channel_names") or [])
                 + ") are in the sensor's own unit, in the channel order of the data file. The RMSE of the whole "
                 f"wrench is over {over} (thesis eq. 18)."
                 + (f" The data file declared {_fmt(', '.join(f'{k[7:]}: {u}' for k, u in d['units'].items()))}; "
                    "values were converted to N and N·m." if d.get("units") else "") + "</p>")
    return "\n".join(parts)


def _matrix(mx: dict | None) -> str:
    if mx is None:
        return ("<p class=\"note\">No calibration matrix could be read from this model (its prediction is not affine "
                "in the readings, or not a matrix of these axes). Its identity is the model file and its SHA-256 "
                "above; load it with the command shown.</p>")
    return (f"<h3>Calibration matrix</h3><p class=\"note\">{_fmt(mx['equation'])}. Row units: the axis unit per raw "
            "unit; offset in the axis unit.</p>"
            + _table(["axis [unit per raw unit]"] + [_fmt(x) for x in mx["columns"]] + ["offset"],
                     [[_fmt(r)] + [_fmt(v, 5) for v in row] + [_fmt(o, 5)]
                      for r, row, o in zip(mx["rows"], mx["matrix"], mx["offset"])]))


# ------------------------------------------------------------------------------------------------- accuracy
def _accuracy(c) -> str:
    v = c.validation
    parts = [f"<p class=\"note\">Folds: {_fmt(v['split'])}. Every error below is on data the fitted calibration did "
             f"not see. Full scale (FS): {_fmt(c.full_scale_source)}. U95 = k·u<sub>c</sub> from the budget (first "
             "page); <i>coverage</i> is the fraction of held-out errors within ±U95."
             + (" auto chose its model on these same folds, so the figures of its choice are slightly optimistic."
                if v.get("reused_auto_predictions") else "") + "</p>",
             _table(["axis", "full scale", "RMS error", "RMS [% FS]", "max error", "max [% FS]", "U95", "U95 [% FS]",
                     "coverage of U95", "coverage of ±2 std"],
                    [[a["axis"], f"{_fmt(a['full_scale'])} {a['unit']}", f"{_fmt(a['rms'])} {a['unit']}",
                      _fmt(a["rms_pct_fs"]), f"{_fmt(a['max'])} {a['unit']}", _fmt(a["max_pct_fs"]),
                      f"{_fmt(a['u95'])} {a['unit']}", _fmt(a["u95_pct_fs"]), f"{100 * a['coverage_u95']:.1f} %",
                      "model gives no std" if a["coverage_std"] is None else f"{100 * a['coverage_std']:.1f} %"]
                     for a in c.accuracy]), _budget_sources(c)]
    if "error_vs_load" in c.figures:
        band = "the specification" if c.spec_pct_fs is not None else "±U95 (no specification given)"
        parts.append(f"<h3>Held-out error against applied load</h3><p class=\"note\">Shaded: {band}; errors beyond it "
                     "in red, the largest drawn last (on top).</p>"
                     f"<img alt=\"Held-out error against applied load\" src=\"{c.figures['error_vs_load']}\">")
    return "\n".join(parts)


def _cases(c) -> str:
    cases = c.cases
    if cases is None or not len(cases.applied):
        return ""
    shown = min(CASES_ON_PAGE, len(cases.applied))
    head = ["#", "group" if cases.group is not None else "row"] + cases.columns(c.axes, " ", "% FS")
    rows = [[str(i + 1), _fmt(cases.group[i] if cases.group is not None else int(cases.first_row[i]))]
            + [_fmt(float(x), 4) for x in cases.applied[i]] + [_fmt(float(x), 4) for x in cases.indicated[i]]
            + [_fmt(float(x), 3) for x in cases.error_pct_fs[i]] for i in range(shown)]
    return ("<section id=\"cases\"><h2>Applied against indicated load (held out), worst first</h2>"
            f"<p class=\"note\">One row per {_fmt(cases.by)}: the applied (reference) load, the load the calibration "
            "indicated when that case was held out, and the error in % of full scale; sorted by the largest error of "
            f"any axis. {shown} of {len(cases.applied)} cases shown; all are in the JSON and in the CSV beside this "
            "page.</p><div class=\"cases\">" + _table(head, rows, long=True) + "</div></section>")


def _choice(c) -> str:
    comp = c.comparison
    plan = comp.get("plan", {})
    units = plan.get("units_name", "fold")
    best = min((r["rmse"] for r in comp.get("rows", []) if r["rmse"] is not None), default=None)
    rows, classes = [], []
    for r in comp.get("rows", []):
        if r["rmse"] is None:
            rows.append([_fmt(r["model"]), _fmt(r["status"] + (f": {r['reason']}" if r.get("reason") else ""))]
                        + [""] * (len(c.axes) + 2))
        else:
            rows.append([_fmt(r["model"]), _fmt(r["rmse"], 4), _fmt(r["rmse_se"], 2), _fmt(r.get("against"))]
                        + [_fmt(x) for x in r["axis_rmse"]])
        classes.append("best" if r["rmse"] is not None and r["rmse"] == best else "")
    head = ["model", "RMSE [N]", "± SE", "against this calibration (paired SE)"] + \
        [f"{a['name']} [{a['unit']}]" for a in c.axes]
    return (f"<p class=\"note\">This calibration beside the stock scikit-learn models a user would try first "
            f"(<code>ftcal.calibrators.stock_baselines</code>), scored by one engine on the same folds "
            f"({_fmt(plan.get('note'))}). Held-out RMSE of the whole wrench, ± its standard error over the {units}s; "
            "'better' or 'worse' only beyond the paired standard error of the difference on the same folds, "
            "'equivalent within noise' otherwise, in the same words whichever side wins.</p>"
            f"<p>{_fmt(comp.get('sentence'))}</p>" + _table(head, rows, classes))


# ------------------------------------------------------------------------------------- readings, range, conditions
def _readings(c) -> str:
    parts = []
    for key, what in (("readings_dropped", "dropped"), ("readings_flagged", "flagged (kept)")):
        items = c.data.get(key) or []
        if items:
            parts.append(f"<h3>Readings {what}: {len(items)}</h3>" + _table(
                ["kind", "file", "line", "channel", "value", "reason"],
                [[_fmt(i.get(f), 7) for f in ("kind", "file", "line", "channel", "value", "reason")]
                 for i in items[:READINGS_ON_PAGE]], long=True)
                + (f"<p class=\"note\">{READINGS_ON_PAGE} of {len(items)} shown; all are in the JSON.</p>"
                   if len(items) > READINGS_ON_PAGE else ""))
    if c.extrapolation:
        parts.append("<h3>Data beyond the model's calibrated range</h3><p class=\"note\">These data are not the "
                     "model's training data: rows whose readings lie beyond the range it was calibrated on, per "
                     "channel, and the largest distance from the range's centre in half-ranges (1 = its edge).</p>"
                     + _table(["channel", "rows beyond", "largest (x the half-range)"],
                              [[_fmt(e["channel"]), f"{e['rows_beyond']} of {e['rows']}",
                                f"{e['largest_x_range']:.2f}x"] for e in c.extrapolation]))
    return "<section id=\"readings\"><h2>Readings checked</h2>" + "".join(parts) + "</section>" if parts else ""


def _range(c) -> str:
    d, r = c.data, c.calibrated_range
    rated = any(a.get("rated") is not None for a in c.accuracy)
    axes = [[f"{ax['name']} [{ax['unit']}]", _fmt(lo), _fmt(hi), _fmt(mm)] + ([_fmt(a["rated"])] if rated else [])
            for ax, lo, hi, mm, a in zip(c.axes, d["wrench_min"], d["wrench_max"], r["wrench_abs_max"], c.accuracy)]
    raw = [[_fmt(n), _fmt(lo), _fmt(hi)] for n, lo, hi in zip(d.get("channel_names") or [], r["raw_min"], r["raw_max"])]
    return ("<p class=\"note\">Readings or loads beyond these were not calibrated (the range check of "
            "<code>ftcal predict</code> flags them).</p>"
            + _table(["axis", "min", "max", "|max|"] + (["rated capacity"] if rated else []), axes)
            + _table(["raw channel", "min", "max"], raw, long=True))


def _conditions(c) -> str:
    d, cond = c.data, c.conditions
    temp_data = None if d["temperature_range"] is None else \
        f"{_fmt(d['temperature_range'][0])} to {_fmt(d['temperature_range'][1])} °C (the data's temperature column)"
    ambient = cond.get("ambient_temperature")
    how_temp = ("the data have no temperature column: add one named <code>temperature</code> [°C] to the data file, "
                "or state the ambient temperature (<code>ambient_temperature: 23 °C</code> in the conditions file, "
                "or the ambient temperature option of <code>ftcal report</code>)")
    rows = []
    for key, label in CONDITION_FIELDS.items():
        if key == "ambient_temperature":
            rows.append([label, _not_stated(ambient if ambient is not None else temp_data, how_temp)])
        elif key in ("location", "notes") and cond.get(key) is None:
            continue
        elif key == "calibration_date" and cond.get(key) is None:
            rows.append([label, _not_stated(None, "issue date " + _fmt(c.identity["date_utc"]))])
        else:
            rows.append([label, _not_stated(cond.get(key))])
    if ambient is not None and temp_data is not None:
        rows.append(["sensor temperature (data)", temp_data])
    data = [["rows", _fmt(d["rows"])], ["raw channels", _fmt(", ".join(d.get("channel_names") or []))]]
    if d.get("groups"):
        names = d.get("group_names")
        data.append(["groups (poses / load configurations)", _fmt(d["groups"]) + (
            ": " + _fmt(", ".join(names[:60])) + (" ..." if len(names) > 60 else "") if names else "")])
    data += [[label, f"{_fmt(d[key])} {unit}"] for key, label, unit in (
        ("max_force_norm", "largest |F|", "N"), ("max_torque_norm", "largest |T|", "N·m")) if d.get(key) is not None]
    data.append(["command", f"<code>{_fmt(c.identity.get('command'))}</code>"])
    return ("<p class=\"note\">From the conditions file beside the data (<code>DATA.conditions.yaml</code> or "
            "<code>.json</code>), a conditions file named on the command line, or the options of the same names.</p>"
            + _table(["", ""], rows) + "<h3>Data</h3>" + _table(["", ""], data))


def _extras(c) -> str:
    parts = []
    pics = [(key, t) for key, t in (("residuals_vs_magnitude", "Held-out error against load magnitude"),
                                     ("residuals_vs_direction", "Held-out error against load direction"))
            if key in c.figures]
    if pics:
        parts.append("<section id=\"residuals\"><h2>Residuals</h2>" + "".join(
            f"<h3>{t}</h3><img alt=\"{t}\" src=\"{c.figures[key]}\">" for key, t in pics) + "</section>")
    tc, tool = c.temperature_coefficients, c.tool
    if tc is None and tool is None:
        return "\n".join(parts)
    parts.append("<section id=\"extras\">")
    channels = c.data.get("channel_names") or []
    if tc is not None:
        parts += [f"<h2>Temperature coefficients</h2><p class=\"note\">raw = f(w)(1 + g ΔT) + o ΔT, ΔT from "
                  f"{_fmt(tc['reference_temperature'])} °C.</p>",
                  _table(["channel", "gain g [1/°C]", "offset o [unit/°C]"],
                         [[_fmt(n), _fmt(g), _fmt(o)] for n, g, o in
                          zip(channels, tc["gain_per_deg"], tc["offset_per_deg"])])]
    if tool is not None:
        parts += ["<h2>Tool</h2>", _table(["", "value"], [
            ["mass", f"{_fmt(tool['mass_kg'])} ± {_fmt(tool['mass_std_error_kg'], 2)} kg"],
            ["centre of mass (sensor frame)", f"{', '.join(_fmt(v) for v in tool['center_of_mass_m'])} m"],
            ["bias", ", ".join(_fmt(b) for b in tool["bias"]) + " [N, N·m]"]])]
    parts.append("</section>")
    return "\n".join(parts)


def render_page(certificate) -> str:
    """The certificate's HTML page: :data:`PAGE` filled with each section's HTML."""
    c = certificate
    return PAGE.substitute(
        title=f"Calibration report: {_fmt(c.sensor)}", summary=_summary(c), calibration=_calibration(c),
        accuracy=_accuracy(c), cases=_cases(c), choice=_choice(c), readings=_readings(c), range=_range(c),
        conditions=_conditions(c), extras=_extras(c))
