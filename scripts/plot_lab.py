#!/usr/bin/python3
"""Charts for haptic-lab's CSV outputs (PNG and SVG side by side).

    scripts/plot_lab.py zwidth grid.csv out/zwidth        -> out/zwidth.png, out/zwidth.svg
    scripts/plot_lab.py transparency sweep.csv out/design -> out/design.png, out/design.svg
    scripts/plot_lab.py run trace.csv out/trace           -> out/trace.png, out/trace.svg
    scripts/plot_lab.py identify response.csv out/bode    -> out/bode.png, out/bode.svg
    scripts/plot_lab.py identify-sweep sweep.csv out/sweep -> out/sweep.png, out/sweep.svg

zwidth: the (K, B) grid, each cell marked by which tests call it stable (Colgate's bound,
the sampled loop's eigenvalues, simulation). transparency: J(B_c) and ||L||inf(B_c) in dB against
B_c on a log axis, with the robust-stability line at 0 dB. run: `haptic-lab run`'s trace over time
in three stacked panels: the tool's position (m), the force on it (N) and the energy the scene
gave to the device and took from it (J), one line per port and axis that moves (columns are read
by name; extra columns are ignored), with the ticks whose flags are set marked on the force panel.
identify: `haptic-lab identify --csv`'s frequency response as a Bode chart, X/F's magnitude (m/N,
log) and phase (degrees) against frequency (Hz, log): the measured harmonics as points, the
identified model as a line through them. identify-sweep: `haptic-lab identify --sweep-csv`'s runs,
the mass's and the damping's relative error (points, solid) and 95 % interval (dashed) against
the excitation's length (s, log), one colour per amplitude (for a device without damping, the
damping panel shows the identified damping's magnitude and interval in N·s/m).

Runs with /usr/bin/python3 and Debian's python3-matplotlib (Agg backend).
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The same data draws the same bytes (no dates, fixed SVG ids): regenerated charts diff cleanly.
plt.rcParams["svg.hashsalt"] = "hapticd"


def read(path, columns=()):
    """The rows of a CSV file; exits with a message naming the file and any missing column."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = [c for c in columns if c not in (reader.fieldnames or [])]
            if missing:
                sys.exit(f"plot_lab: {path}: missing column(s) {', '.join(missing)}")
            return list(reader)
    except OSError as error:
        sys.exit(f"plot_lab: {path}: {error.strerror}")


RUN_COLUMNS = ["port", "time_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n", "flags",
               "energy_to_device_j", "energy_from_device_j"]
PORT_COLOURS = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860", "#da8bc3", "#8c8c8c"]
AXIS_STYLES = {"x": "-", "y": "--", "z": ":"}


def value(row, column, line):
    try:
        return float(row[column])
    except (TypeError, ValueError):
        sys.exit(f"plot_lab: line {line}: column {column}: not a number: {row[column]!r}")


def run(rows, out):
    """haptic-lab run's trace: position, force and energy against time, per port."""
    ports = {}
    for line, r in enumerate(rows, start=2):
        p = ports.setdefault(r["port"], {k: [] for k in RUN_COLUMNS[1:]})
        for k in RUN_COLUMNS[1:]:
            p[k].append(value(r, k, line))
    if not ports:
        sys.exit("plot_lab: the trace has no rows")

    def moves(values, floor):
        finite = [v for v in values if math.isfinite(v)]
        return len(finite) != len(values) or (finite and max(finite) - min(finite) > floor)

    fig, (pos, force, energy) = plt.subplots(3, 1, figsize=(7.5, 7.0), sharex=True)
    for i, (port, p) in enumerate(sorted(ports.items(), key=lambda kv: int(float(kv[0])))):
        colour = PORT_COLOURS[i % len(PORT_COLOURS)]
        t = p["time_s"]
        for axis in "xyz":
            if moves(p[axis + "_m"], 1e-9):  # 1 nm: below it the axis is taken as still
                pos.plot(t, p[axis + "_m"], color=colour, ls=AXIS_STYLES[axis], lw=1.1,
                         label=f"port {port} {axis}")
            if moves(p["f" + axis + "_n"], 1e-9) or any(v != 0.0 for v in p["f" + axis + "_n"]):
                force.plot(t, p["f" + axis + "_n"], color=colour, ls=AXIS_STYLES[axis], lw=1.1,
                           label=f"port {port} F{axis}")
        energy.plot(t, p["energy_to_device_j"], color=colour, lw=1.1, label=f"port {port} to the device")
        energy.plot(t, p["energy_from_device_j"], color=colour, lw=1.1, ls="--",
                    label=f"port {port} from the device")
        flagged = [time for time, f in zip(t, p["flags"]) if f != 0]
        if flagged:
            force.plot(flagged, [0.0] * len(flagged), "|", color="#d62728", ms=8,
                       label=f"port {port}: flags set ({len(flagged)} ticks)")
    for ax, label in ((pos, "tool position p_WT [m]"), (force, "force F_T_W [N]"),
                      (energy, "energy [J]")):
        ax.set_ylabel(label)
        ax.grid(True, lw=0.4, alpha=0.5)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="best")
        else:
            ax.text(0.5, 0.5, "nothing moves", transform=ax.transAxes, ha="center", color="#777777")
    energy.set_xlabel("time [s]")
    pos.set_title(f"haptic-lab run: position, force and energy ({os.path.basename(out)})")
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(out + ".svg", metadata={"Date": None})


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
    fig.savefig(out + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(out + ".svg", metadata={"Date": None})


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
    # Every hold model's ‖L‖∞, where the CSV has them: the verdict near the optimum depends on it.
    holds = [("delay", "e^(−sT/2)", ":"), ("pade", "Padé", "-."), ("exact", "exact hold", "--")]
    for name, label, style in holds:
        column = "robust_norm_db_" + name
        if column in rows[0]:
            twin.plot(b, [float(r[column]) for r in rows], color="#c44e52", lw=0.8, ls=style,
                      label="‖L‖∞, " + label)
    twin.axhline(0.0, color="0.5", lw=0.8)
    twin.set_ylabel("‖L‖∞ [dB] (robust below 0 dB)")
    ax.set_title("Transparency and robust stability (haptic-lab transparency)")
    fig.legend(fontsize=8, loc="upper right", bbox_to_anchor=(0.86, 0.86))
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(out + ".svg", metadata={"Date": None})


def identify(rows, out):
    f = [float(r["frequency_hz"]) for r in rows]
    fig, (mag, phase) = plt.subplots(2, 1, figsize=(7.0, 6.0), sharex=True)
    mag.loglog(f, [float(r["model_m_per_n"]) for r in rows], color="#4c72b0", label="identified model")
    mag.loglog(f, [float(r["measured_m_per_n"]) for r in rows], "o", color="#c44e52", ms=4,
               label="measured (periods averaged)")
    mag.set_ylabel("|X/F| [m/N]")
    mag.grid(True, which="both", lw=0.3)
    mag.legend(fontsize=8)
    # Phases unwrapped from the lowest harmonic, so a delay reads as a straight fall.
    def unwrapped(column):
        values, offset, previous = [], 0.0, None
        for r in rows:
            v = float(r[column])
            if previous is not None:
                while v + offset - previous > 180.0:
                    offset -= 360.0
                while v + offset - previous < -180.0:
                    offset += 360.0
            previous = v + offset
            values.append(previous)
        return values
    phase.semilogx(f, unwrapped("model_phase_deg"), color="#4c72b0")
    phase.semilogx(f, unwrapped("measured_phase_deg"), "o", color="#c44e52", ms=4)
    phase.set_ylabel("phase [deg]")
    phase.set_xlabel("frequency [Hz]")
    phase.grid(True, which="both", lw=0.3)
    mag.set_title("Frequency response of the identified axis (haptic-lab identify)")
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(out + ".svg", metadata={"Date": None})


def identify_sweep(rows, out):
    # A device without damping of its own (004's joystick) has no relative damping error: that
    # panel shows the identified damping's magnitude and interval in N·s/m instead (the newer
    # columns; a sweep written before them has a damped device and needs neither).
    absolute = all(math.isnan(float(r["damping_error"])) for r in rows)
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2), sharey=not absolute)
    amplitudes = sorted({float(r["amplitude_n"]) for r in rows})
    colours = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3"]
    for ax, name in zip(axes, ["mass", "damping"]):
        error, half = (name + "_error", name + "_half_width")
        if name == "damping" and absolute:
            error, half = ("damping_n_s_m", "damping_half_width_n_s_m")
        for i, a in enumerate(amplitudes):
            mine = sorted((r for r in rows if float(r["amplitude_n"]) == a), key=lambda r: float(r["excitation_s"]))
            t = [float(r["excitation_s"]) for r in mine]
            colour = colours[i % len(colours)]
            # An error of exactly 0 cannot be drawn on a log axis: floored at 1e-6.
            ax.loglog(t, [max(1e-6, abs(float(r[error]))) for r in mine], "o-", color=colour, ms=4,
                      label=f"{a:g} N: error")
            ax.loglog(t, [float(r[half]) for r in mine], "--", color=colour, lw=1,
                      label=f"{a:g} N: 95 % interval")
        if name == "damping" and absolute:
            ax.set_title("damping: the device has none; |identified| [N·s/m]")
        else:
            ax.set_title(f"{name}: relative to the device's own")
        ax.set_xlabel("excitation [s] (ramps, settling and the fitted periods)")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("|identified − model| / model, and the interval's half")
    axes[1].legend(fontsize=7, ncol=2)
    fig.suptitle("Identification's error against the excitation's length (haptic-lab identify --sweep-csv)")
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120, metadata={"Software": None})
    fig.savefig(out + ".svg", metadata={"Date": None})


CHARTS = {
    "zwidth": (zwidth, ["stiffness_n_m", "damping_n_s_m", "passive", "eigen_stable", "simulation_stable"]),
    "transparency": (transparency, ["controller_damping_n_s_m", "transparency_index", "robust_norm_db"]),
    "run": (run, RUN_COLUMNS),
    "identify-sweep": (identify_sweep, ["amplitude_n", "excitation_s", "mass_error", "damping_error",
                                        "mass_half_width", "damping_half_width"]),
    "identify": (identify, ["frequency_hz", "measured_m_per_n", "measured_phase_deg", "model_m_per_n",
                            "model_phase_deg"]),
}

if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in CHARTS:
        sys.exit(__doc__)
    chart, columns = CHARTS[sys.argv[1]]
    chart(read(sys.argv[2], columns), sys.argv[3])
