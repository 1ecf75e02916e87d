#!/usr/bin/env python3
"""Charts for haptic-lab's CSV outputs (PNG and SVG side by side).

    scripts/plot_lab.py zwidth grid.csv out/zwidth        -> out/zwidth.png, out/zwidth.svg
    scripts/plot_lab.py transparency sweep.csv out/design -> out/design.png, out/design.svg

zwidth: the (K, B) grid, each cell marked by which tests call it stable (Colgate's bound,
the sampled loop's eigenvalues, simulation). transparency: J(B_c) and ||L||inf(B_c) in dB against
B_c on a log axis, with the robust-stability line at 0 dB.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def zwidth(rows, out):
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    styles = [
        ("passive (Colgate)", lambda r: r["passive"] == "1", "s", "#2ca02c"),
        ("stable: eigenvalues and simulation", lambda r: r["passive"] != "1" and r["eigen_stable"] == "1" and r["simulation_stable"] == "1", "o", "#4c72b0"),
        ("stable by eigenvalues only", lambda r: r["eigen_stable"] == "1" and r["simulation_stable"] != "1", "^", "#dd8452"),
        ("stable in simulation only", lambda r: r["eigen_stable"] != "1" and r["simulation_stable"] == "1", "v", "#c44e52"),
        ("unstable", lambda r: r["eigen_stable"] != "1" and r["simulation_stable"] != "1", "x", "#999999"),
    ]
    for label, test, marker, colour in styles:
        cells = [r for r in rows if test(r)]
        if cells:
            # B = 0 is drawn at the grid's smallest positive damping / 3 on the log axis.
            positive = [float(r["damping_n_s_m"]) for r in rows if float(r["damping_n_s_m"]) > 0]
            floor = min(positive) / 3 if positive else 1e-3
            ax.scatter([max(float(r["damping_n_s_m"]), floor) for r in cells],
                       [float(r["stiffness_n_m"]) for r in cells], marker=marker, color=colour, label=label, s=22)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall damping B [N·s/m] (B = 0 drawn at the left edge)")
    ax.set_ylabel("wall stiffness K [N/m]")
    ax.set_title("Z-width (haptic-lab zwidth)")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120)
    fig.savefig(out + ".svg")


def transparency(rows, out):
    b = [float(r["controller_damping_n_s_m"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4.0))
    ax.plot(b, [float(r["transparency_index"]) for r in rows], color="#4c72b0", label="J (eq. 11)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("controller damping B_c [N·s/m]")
    ax.set_ylabel("transparency index J")
    twin = ax.twinx()
    twin.plot(b, [float(r["robust_norm_db"]) for r in rows], color="#c44e52", label="‖L‖∞ (eq. 17)")
    twin.axhline(0.0, color="#c44e52", lw=0.8, ls="--")
    twin.set_ylabel("‖L‖∞ [dB] (robust below 0 dB)")
    ax.set_title("Transparency and robust stability (haptic-lab transparency)")
    fig.legend(fontsize=8, loc="upper right", bbox_to_anchor=(0.86, 0.86))
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120)
    fig.savefig(out + ".svg")


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("zwidth", "transparency"):
        sys.exit(__doc__)
    {"zwidth": zwidth, "transparency": transparency}[sys.argv[1]](read(sys.argv[2]), sys.argv[3])
