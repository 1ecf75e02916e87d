#!/usr/bin/python3
"""Charts for `haptic-lab study`'s output: error against run time, one chart per case.

    scripts/plot_study.py DIR

reads DIR/study.csv (one row per case, variant, scheme and step), DIR/cases.csv (each case's
title, source, observable and group) and DIR/references.csv (how each case's reference was
obtained), and writes DIR/charts/<case>.png and .svg and DIR/charts/overview.png and .svg (a grid
of every case, small).

Each chart is log-log: x is the CPU time the run took per simulated second (s/s), y its error
relative to the reference (max |observable - reference| / max |reference|). One line per scheme
(and, for fidelity cases, per model variant), its points joined in step order and labelled at both
ends with the step. A run that went unstable (or did not finish, or whose error is above the clip
level of 10) is drawn as a hollow red-edged marker on the shaded band at the top, so the chart
shows where each scheme stops working. A zero error is drawn at the floor (1e-16). Where the
reference is not exact, a dashed line marks how far the reference itself has converged
(|ref(h) - ref(2h)| / scale): errors below it are not resolved.

Runs with /usr/bin/python3 and Debian's python3-matplotlib (Agg backend); nothing else.
"""
import textwrap
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from plot_common import InputError, flag, number, read_table  # noqa: E402

# The same data draws the same bytes (no dates, fixed SVG ids): regenerated charts diff cleanly.
plt.rcParams["svg.hashsalt"] = "hapticd"
from matplotlib.lines import Line2D  # noqa: E402

STUDY_COLUMNS = ["case", "group", "variant", "scheme", "step_s", "error", "relative_error",
                 "cpu_s_per_sim_s", "stable", "energy_drift", "note"]
CASE_COLUMNS = ["name", "title", "source", "observable", "group"]
REFERENCE_COLUMNS = ["case", "exact", "scheme", "step_s", "convergence", "scale"]

CLIP = 10.0    # relative errors above this (and unstable runs) are drawn on the band at the top
FLOOR = 1e-16  # a zero relative error is drawn here
BAND_SHARE = 0.09  # the band's share of the error axis' height

# One colour per scheme (the study's names, study.hpp scheme_name); others cycle through the rest.
SCHEME_COLOURS = {
    "explicit_euler": "#c44e52",
    "semi_implicit_euler": "#dd8452",
    "trapezoidal": "#55a868",
    "rk4": "#4c72b0",
    "implicit_euler": "#8172b3",
    "exact_zoh": "#222222",
}
SPARE_COLOURS = ["#937860", "#da8bc3", "#8c8c8c", "#ccb974", "#64b5cd", "#2ca02c", "#17becf"]
LINE_STYLES = ["-", "--", ":", "-."]
MARKERS = ["o", "s", "^", "D", "v", "P", "X"]


def load(directory):
    """The study's rows grouped by case, the cases in cases.csv's order, and the references."""
    study_path = os.path.join(directory, "study.csv")
    cases_path = os.path.join(directory, "cases.csv")
    references_path = os.path.join(directory, "references.csv")
    cases = []
    for line, row in read_table(cases_path, CASE_COLUMNS):
        if not row["name"].strip():
            raise InputError(f"{cases_path}:{line}: column name: empty")
        cases.append({k: row[k].strip() for k in CASE_COLUMNS})
    runs = {}
    for line, row in read_table(study_path, STUDY_COLUMNS):
        step = number(study_path, line, row, "step_s")
        if not (step > 0 and math.isfinite(step)):
            raise InputError(f"{study_path}:{line}: column step_s: must be finite and > 0, got {step}")
        runs.setdefault(row["case"].strip(), []).append({
            "variant": row["variant"].strip(),
            "scheme": row["scheme"].strip(),
            "step": step,
            "relative_error": number(study_path, line, row, "relative_error"),
            "cpu": number(study_path, line, row, "cpu_s_per_sim_s"),
            "stable": flag(study_path, line, row, "stable"),
        })
    references = {}
    for line, row in read_table(references_path, REFERENCE_COLUMNS):
        references[row["case"].strip()] = {
            "exact": flag(references_path, line, row, "exact"),
            "scheme": row["scheme"].strip(),
            "step": number(references_path, line, row, "step_s"),
            "convergence": number(references_path, line, row, "convergence"),
            "scale": number(references_path, line, row, "scale"),
        }
    known = {c["name"] for c in cases}
    for name in runs:
        if name not in known:
            print(f"plot_study: {study_path}: case {name!r} is not in {cases_path}; "
                  "charted under its name", file=sys.stderr)
            cases.append({"name": name, "title": name, "source": "", "observable": "", "group": ""})
    return cases, runs, references


def step_label(step):
    """1e-3 s, 2.5e-4 s: the step as a reader would write it."""
    mantissa, exponent = f"{step:.1e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)} s"


def series_style(case_runs):
    """(key -> colour, linestyle, marker, label) for each (variant, scheme) line of a case: colour
    by scheme and line style by variant, or colour by variant when the case has one scheme."""
    schemes = list(dict.fromkeys(r["scheme"] for r in case_runs))
    variants = list(dict.fromkeys(r["variant"] for r in case_runs))
    by_variant = len(schemes) == 1 and len(variants) > 1
    styles = {}
    spare = iter(SPARE_COLOURS * 4)
    scheme_colour = {s: SCHEME_COLOURS.get(s) or next(spare) for s in schemes}
    for vi, variant in enumerate(variants):
        for si, scheme in enumerate(schemes):
            if by_variant:
                colour = (list(SCHEME_COLOURS.values()) + SPARE_COLOURS)[vi % 13]
                style, marker = "-", MARKERS[vi % len(MARKERS)]
                label = variant
            else:
                colour = scheme_colour[scheme]
                style = LINE_STYLES[vi % len(LINE_STYLES)]
                marker = MARKERS[si % len(MARKERS)]
                label = scheme if len(variants) <= 1 or not variant else f"{variant} · {scheme}"
            styles[(variant, scheme)] = (colour, style, marker, label)
    return styles


def draw_case(ax, case, case_runs, reference, compact=False):
    """One case's chart on `ax`. Returns the legend handles."""
    styles = series_style(case_runs)
    positive_cpu = [r["cpu"] for r in case_runs if r["cpu"] > 0 and math.isfinite(r["cpu"])]
    x_missing = min(positive_cpu) / 2 if positive_cpu else 1e-3  # where a run with no time goes
    lowest = CLIP
    for r in case_runs:
        if r["stable"] and math.isfinite(r["relative_error"]) and r["relative_error"] <= CLIP:
            lowest = min(lowest, max(r["relative_error"], FLOOR))
    level = float("nan")  # the reference's convergence, relative
    if reference is not None and not reference["exact"] and reference["scale"] > 0:
        level = reference["convergence"] / reference["scale"]
        if math.isfinite(level) and level > 0:
            level = max(level, FLOOR)
            lowest = min(lowest, level)
    bottom = lowest / 10.0
    # The band spans BAND_SHARE of the axis (log scale): CLIP up to band_top; markers in its middle.
    decades = math.log10(CLIP / bottom)
    band_decades = max(0.4, decades * BAND_SHARE / (1.0 - BAND_SHARE))
    band_top = CLIP * 10.0 ** band_decades
    band_y = CLIP * 10.0 ** (band_decades / 2.0)
    handles = []
    any_off_chart = False
    for key, (colour, style, marker, label) in styles.items():
        points = sorted((r for r in case_runs if (r["variant"], r["scheme"]) == key),
                        key=lambda r: -r["step"])  # largest step (cheapest) first
        if not points:
            continue
        good, off = [], []
        for r in points:
            x = r["cpu"] if r["cpu"] > 0 and math.isfinite(r["cpu"]) else x_missing
            e = r["relative_error"]
            if r["stable"] and math.isfinite(e) and e <= CLIP:
                y = max(e, FLOOR)
                good.append((x, y, r["step"]))
            else:
                off.append((x, r["step"]))
        ms = 3.5 if compact else 5.5
        if good:
            ax.plot([p[0] for p in good], [p[1] for p in good], ls=style, marker=marker, color=colour,
                    ms=ms, lw=1.0 if compact else 1.4)
            if not compact:
                # The first (largest) step to the left of its point, the last to the right.
                ax.annotate(step_label(good[0][2]), good[0][:2], textcoords="offset points",
                            xytext=(-5, 2), ha="right", fontsize=6.5, color=colour)
                if len(good) > 1:
                    ax.annotate(step_label(good[-1][2]), good[-1][:2], textcoords="offset points",
                                xytext=(5, 2), ha="left", fontsize=6.5, color=colour)
        if off:
            any_off_chart = True
            ax.scatter([p[0] for p in off], [band_y] * len(off), marker=marker, s=(ms * 1.6) ** 2,
                       facecolors="none", edgecolors="#d62728", linewidths=1.1, zorder=3)
            # The scheme's colour inside the hollow marker says whose run it was.
            ax.scatter([p[0] for p in off], [band_y] * len(off), marker=".", s=ms ** 2 * 0.6,
                       color=colour, zorder=4)
            if not compact and not good:
                ax.annotate(step_label(off[0][1]), (off[0][0], band_y), textcoords="offset points",
                            xytext=(4, -9), fontsize=6.5, color=colour)
        handles.append(Line2D([], [], color=colour, ls=style, marker=marker, ms=ms, label=label))
    ax.axhspan(CLIP, band_top, color="#d62728", alpha=0.08, lw=0)
    ax.axhline(CLIP, color="#d62728", lw=0.6)
    if not compact:
        ax.text(0.995, CLIP, f"above: unstable, unfinished or error > {CLIP:g}  ",
                transform=ax.get_yaxis_transform(), fontsize=6.5, color="#d62728", ha="right",
                va="top")
    if any(r["stable"] and r["relative_error"] == 0.0 for r in case_runs):
        handles.append(Line2D([], [], ls="none", label=f"(an error of 0 is drawn at {FLOOR:g})"))
    if any_off_chart:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec="#d62728",
                              label="unstable / off the chart"))
    if math.isfinite(level) and level > 0:
        ax.axhline(level, color="#555555", lw=0.9, ls="--")
        handles.append(Line2D([], [], color="#555555", ls="--",
                              label=f"reference converged to {level:.1e} "
                                    f"({reference['scheme']}, {step_label(reference['step'])})"))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(bottom, band_top)
    ax.set_xmargin(0.04 if compact else 0.12)  # room for the step labels
    if compact:
        ax.tick_params(labelsize=6)
    else:
        ax.set_xlabel("CPU time per simulated second [s/s]")
        ax.set_ylabel("relative error (max |x - x_ref| / max |x_ref|)")
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
    if not case_runs:
        ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center")
    return handles


def save(fig, path_without_extension):
    fig.savefig(path_without_extension + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(path_without_extension + ".svg", metadata={"Date": None})
    plt.close(fig)


def subtitle(case, reference):
    parts = [p for p in (case.get("source"), case.get("observable")) if p]
    if reference is not None:
        parts.append("exact reference" if reference["exact"] else
                     f"reference: {reference['scheme']} at {step_label(reference['step'])}")
    return "; ".join(parts)


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    directory = argv[1]
    if not os.path.isdir(directory):
        raise InputError(f"{directory}: not a directory")
    cases, runs, references = load(directory)
    charted = [c for c in cases if runs.get(c["name"])]
    for c in cases:
        if not runs.get(c["name"]):
            print(f"plot_study: case {c['name']!r} has no rows in study.csv; no chart", file=sys.stderr)
    if not charted:
        raise InputError(f"{os.path.join(directory, 'study.csv')}: no rows for any case")
    out = os.path.join(directory, "charts")
    os.makedirs(out, exist_ok=True)
    written = []
    for case in charted:
        reference = references.get(case["name"])
        fig, ax = plt.subplots(figsize=(9.0, 4.8))
        handles = draw_case(ax, case, runs[case["name"]], reference)
        wrapped = "\n".join(textwrap.wrap(subtitle(case, reference), 110))
        ax.set_title(f"{case['title']}\n{wrapped}", fontsize=9)
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.tight_layout()
        save(fig, os.path.join(out, case["name"]))
        written.append(case["name"])

    columns = min(4, len(charted))
    rows = math.ceil(len(charted) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.4 * columns, 2.7 * rows + 0.8), squeeze=False)
    legend = {}
    for ax, case in zip(axes.flat, charted):
        own = []  # lines the shared legend does not explain (variants of a fidelity case)
        for h in draw_case(ax, case, runs[case["name"]], references.get(case["name"]), compact=True):
            if h.get_label() in SCHEME_COLOURS or h.get_label() == "unstable / off the chart":
                legend.setdefault(h.get_label(), h)
            elif not h.get_label().startswith("reference"):
                own.append(h)
        if own:
            ax.legend(handles=own, fontsize=5, loc="lower left", framealpha=0.8)
        ax.set_title("\n".join(textwrap.wrap(case["title"], 48)[:3]), fontsize=7)
    for ax in list(axes.flat)[len(charted):]:
        ax.axis("off")
    fig.supxlabel("CPU time per simulated second [s/s]", fontsize=8)
    fig.supylabel("relative error", fontsize=8)
    if legend:
        fig.legend(handles=list(legend.values()), loc="upper center", ncol=min(7, len(legend)),
                   fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / (2.7 * rows + 0.8)))
    save(fig, os.path.join(out, "overview"))
    print(f"plot_study: wrote {len(written)} case charts and the overview to {out}/ (PNG and SVG)")


if __name__ == "__main__":
    try:
        main(sys.argv)
    except InputError as error:
        sys.exit(f"plot_study: {error}")
