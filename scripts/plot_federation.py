#!/usr/bin/python3
"""Chart of the federation's transparency against one-way delay (federation_transparency's output).

    scripts/plot_federation.py DIR

reads DIR/transparency.csv (one row per coupling, delay, loss and layer switch) and, when it is
there, DIR/boundary.csv (the smallest delay at which each coupling without the passivity layer
creates energy), and writes DIR/transparency.png and DIR/transparency.svg.

Two panels, one per coupling (tool contact, shared mass), each in two rows: the force error
(relative) above the position error (mm). x is the one-way delay on a log scale, with 0 ms placed
at the left past a break. One line per (layer on/off, loss): colour by the layer, line style and
marker by the loss. A run that went unstable (non-finite, or its couplings created more than
10 mJ) is drawn as a hollow red-edged marker on the shaded band at the top of its panel, not as a
number; a dotted vertical line marks where the coupling without the layer turns active. An error
of exactly 0 (the no-network reference itself) is drawn at the bottom edge.

Runs with /usr/bin/python3 and Debian's python3-matplotlib (Agg backend); nothing else.
"""
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

COLUMNS = ["coupling", "sites", "delay_ms", "loss", "layer", "stable", "force_error",
           "position_error_m", "max_position_error_m", "energy_created_J", "largest_force_N", "note"]
BOUNDARY_COLUMNS = ["coupling", "sites", "seconds", "searched_up_to_ms", "boundary_delay_ms",
                    "energy_created_J", "note"]

COUPLINGS = [
    ("tool_contact", "Tool on remote tool (avatar contact)",
     "force error: RMS |F_A + F_B| / RMS |F_A|",
     "position error: RMS |Δp − Δp_ref|, Δp = p_B − p_A [mm]"),
    ("shared_mass", "Shared mass (coupled copies, 2 sites)",
     "force error: RMS |F_A − F_A,ref| / RMS |F_A,ref|",
     "position error: RMS |p_copy,A − p_copy,B| [mm]"),
]
LAYER_COLOURS = {True: "#4c72b0", False: "#c44e52"}
LOSS_STYLES = ["-", "--", ":", "-."]
LOSS_MARKERS = ["o", "s", "^", "D"]
BAND_SHARE = 0.10  # the unstable band's share of each axis' height
ZERO_SHIFT = 1.25  # an error of 0 is drawn this factor above the bottom edge (log axis)


def load(directory):
    """The runs grouped by coupling, and the boundaries by coupling ({} without boundary.csv)."""
    path = os.path.join(directory, "transparency.csv")
    known = {c[0] for c in COUPLINGS}
    runs = {}
    for line, row in read_table(path, COLUMNS):
        coupling = row["coupling"].strip()
        if coupling not in known:
            print(f"plot_federation: {path}:{line}: coupling {coupling!r} is not one this chart draws "
                  f"({', '.join(sorted(known))}); left out", file=sys.stderr)
            continue
        delay = number(path, line, row, "delay_ms")
        if not (delay >= 0 and math.isfinite(delay)):
            raise InputError(f"{path}:{line}: column delay_ms: must be finite and >= 0, got {delay}")
        loss = number(path, line, row, "loss")
        if not 0 <= loss <= 1:
            raise InputError(f"{path}:{line}: column loss: must be 0 to 1, got {loss}")
        runs.setdefault(coupling, []).append({
            "delay": delay,
            "loss": loss,
            "layer": flag(path, line, row, "layer"),
            "stable": flag(path, line, row, "stable"),
            "force_error": number(path, line, row, "force_error"),
            "position_error": number(path, line, row, "position_error_m") * 1e3,  # mm
        })
    boundaries = {}
    boundary_path = os.path.join(directory, "boundary.csv")
    if os.path.isfile(boundary_path):
        for line, row in read_table(boundary_path, BOUNDARY_COLUMNS):
            boundaries.setdefault(row["coupling"].strip(), []).append({
                "sites": int(number(boundary_path, line, row, "sites")),
                "delay": number(boundary_path, line, row, "boundary_delay_ms"),
                "searched": number(boundary_path, line, row, "searched_up_to_ms"),
            })
    return runs, boundaries


class DelayAxis:
    """Delays on a log axis, 0 placed a step to the left of the smallest positive delay."""

    def __init__(self, delays):
        positive = sorted(d for d in delays if d > 0)
        self.first = positive[0] if positive else 1.0
        self.last = positive[-1] if positive else 1.0
        self.zero = self.first / 3.0

    def x(self, delay):
        return delay if delay > 0 else self.zero

    def decorate(self, ax, delays, labels):
        ax.set_xscale("log")
        ticks = sorted(set(delays))
        ax.set_xticks([self.x(d) for d in ticks])
        ax.set_xticklabels([f"{d:g}" for d in ticks] if labels else [], fontsize=7)
        ax.minorticks_off()
        ax.set_xlim(self.zero / 1.5, self.last * 1.5)
        if any(d == 0 for d in delays) and self.first > self.zero:
            # The break between 0 and the log scale.
            cut = math.sqrt(self.zero * self.first)
            ax.axvline(cut, color="#bbbbbb", lw=0.6, ls=(0, (2, 2)))


def split_runs(points):
    """Consecutive stable points as separate segments, so a line never joins across an unstable
    run."""
    segments, current = [], []
    for p in points:
        if p["stable"] and math.isfinite(p["value"]):
            current.append(p)
        elif current:
            segments.append(current)
            current = []
    if current:
        segments.append(current)
    return segments


def draw(ax, runs, measure, axis, boundaries, labels):
    """One measure of one coupling on `ax`; returns whether anything was unstable or zero."""
    losses = sorted({r["loss"] for r in runs})
    stable_values = [r[measure] for r in runs
                     if r["stable"] and math.isfinite(r[measure]) and r[measure] > 0]
    lowest = min(stable_values) if stable_values else 1e-3
    highest = max(stable_values) if stable_values else 1.0
    bottom = lowest / 3.0
    top = max(highest * 2.0, bottom * 10.0)
    decades = math.log10(top / bottom)
    band_decades = max(0.35, decades * BAND_SHARE / (1.0 - BAND_SHARE))
    band_top = top * 10.0 ** band_decades
    band_y = top * 10.0 ** (band_decades / 2.0)
    zero_y = bottom * ZERO_SHIFT
    any_unstable = any_zero = False
    for layer in (True, False):
        for li, loss in enumerate(losses):
            colour = LAYER_COLOURS[layer]
            style = LOSS_STYLES[li % len(LOSS_STYLES)]
            marker = LOSS_MARKERS[li % len(LOSS_MARKERS)]
            points = sorted(({"delay": r["delay"], "value": r[measure], "stable": r["stable"]}
                             for r in runs if r["layer"] == layer and r["loss"] == loss),
                            key=lambda p: p["delay"])
            if not points:
                continue
            for segment in split_runs(points):
                ys = []
                for p in segment:
                    if p["value"] > 0:
                        ys.append(p["value"])
                    else:
                        ys.append(zero_y)
                        any_zero = True
                # Without the layer: hollow markers and a thinner line, drawn over the layer's
                # lines, so that where the two agree both stay visible.
                ax.plot([axis.x(p["delay"]) for p in segment], ys, ls=style, marker=marker,
                        color=colour, ms=6.0 if not layer else 4.5, lw=0.9 if not layer else 1.5,
                        mfc="none" if not layer else colour, zorder=2.5 if not layer else 2)
            off = [axis.x(p["delay"]) for p in points
                   if not (p["stable"] and math.isfinite(p["value"]))]
            if off:
                any_unstable = True
                # Side by side within the band: one row per line, so markers do not hide each other.
                row = (0 if layer else 2) + li
                y = band_y * 10.0 ** ((row - 1.5) * band_decades * 0.18)
                ax.scatter(off, [y] * len(off), marker=marker, s=40, facecolors="none",
                           edgecolors="#d62728", linewidths=1.0, zorder=3)
                ax.scatter(off, [y] * len(off), marker=".", s=9, color=colour, zorder=4)
    ax.axhspan(top, band_top, color="#d62728", alpha=0.08, lw=0)
    ax.axhline(top, color="#d62728", lw=0.6)
    if labels:
        ax.text(0.99, top, "unstable without a number ", transform=ax.get_yaxis_transform(),
                fontsize=6.5, color="#d62728", ha="right", va="top")
    for b in boundaries:
        if b["delay"] >= 0 and b["sites"] == 2:
            ax.axvline(axis.x(b["delay"]), color=LAYER_COLOURS[False], lw=0.9, ls=":")
            ax.annotate(f"{b['delay']:g} ms", (axis.x(b["delay"]), 0.0),
                        xycoords=ax.get_xaxis_transform(), textcoords="offset points",
                        xytext=(2, 3), fontsize=6.5, color=LAYER_COLOURS[False])
    ax.set_yscale("log")
    ax.set_ylim(bottom, band_top)
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    ax.tick_params(labelsize=7)
    return any_unstable, any_zero


def boundary_text(boundaries):
    parts = []
    for b in sorted(boundaries, key=lambda b: b["sites"]):
        if b["delay"] >= 0:
            parts.append(f"active from {b['delay']:g} ms ({b['sites']} sites)")
        else:
            parts.append(f"passive up to {b['searched']:g} ms ({b['sites']} sites)")
    return "without the layer: " + ", ".join(parts) if parts else ""


def save(fig, path_without_extension):
    fig.savefig(path_without_extension + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(path_without_extension + ".svg", metadata={"Date": None})
    plt.close(fig)


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    directory = argv[1]
    if not os.path.isdir(directory):
        raise InputError(f"{directory}: not a directory")
    runs, boundaries = load(directory)
    if not runs:
        raise InputError(f"{os.path.join(directory, 'transparency.csv')}: no rows to chart")
    # The boundaries' delays on the same axis (a boundary below every run's positive delay stays
    # right of the break).
    delays = [r["delay"] for rows in runs.values() for r in rows]
    axis = DelayAxis(delays + [b["delay"] for rows in boundaries.values() for b in rows
                               if b["delay"] > 0])
    fig, axes = plt.subplots(2, 2, figsize=(11.0, 7.2), squeeze=False)
    any_unstable = any_zero = False
    for column, (name, title, force_label, position_label) in enumerate(COUPLINGS):
        coupling_runs = runs.get(name, [])
        for row, (measure, label) in enumerate((("force_error", force_label),
                                                ("position_error", position_label))):
            ax = axes[row][column]
            if not coupling_runs:
                ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center")
                ax.set_xticks([])
                ax.set_yticks([])
                continue
            unstable, zero = draw(ax, coupling_runs, measure, axis, boundaries.get(name, []),
                                  labels=True)
            any_unstable |= unstable
            any_zero |= zero
            axis.decorate(ax, [r["delay"] for r in coupling_runs], labels=row == 1)
            ax.set_ylabel(label, fontsize=7.5)
            if row == 0:
                note = boundary_text(boundaries.get(name, []))
                ax.set_title(title + (f"\n{note}" if note else ""), fontsize=9)
            else:
                ax.set_xlabel("one-way delay [ms] (log; 0 left of the break)", fontsize=8)
    losses = sorted({r["loss"] for rows in runs.values() for r in rows})
    handles = []
    for layer in (True, False):
        for li, loss in enumerate(losses):
            handles.append(Line2D([], [], color=LAYER_COLOURS[layer],
                                  ls=LOSS_STYLES[li % len(LOSS_STYLES)],
                                  marker=LOSS_MARKERS[li % len(LOSS_MARKERS)],
                                  ms=4.5 if layer else 6.0, lw=1.5 if layer else 0.9,
                                  mfc=LAYER_COLOURS[layer] if layer else "none",
                                  label=f"layer {'on' if layer else 'off'}, {100 * loss:g} % loss"))
    if any_unstable:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec="#d62728",
                              label="unstable (non-finite or > 10 mJ created)"))
    if any(boundaries.values()):
        handles.append(Line2D([], [], color=LAYER_COLOURS[False], ls=":",
                              label="stability boundary without the layer (2 sites)"))
    if any_zero:
        handles.append(Line2D([], [], ls="none", label="(an error of 0 is drawn at the bottom)"))
    fig.legend(handles=handles, loc="lower center", ncol=min(4, len(handles)), fontsize=7.5,
               frameon=False)
    fig.suptitle("Federation transparency against one-way delay (lockstep sites at 1 kHz)",
                 fontsize=10.5)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    out = os.path.join(directory, "transparency")
    save(fig, out)
    print(f"plot_federation: wrote {out}.png and {out}.svg")


if __name__ == "__main__":
    try:
        main(sys.argv)
    except InputError as error:
        sys.exit(f"plot_federation: {error}")
