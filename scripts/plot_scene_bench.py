#!/usr/bin/env python3
"""Draws docs/img/scene_tick_costs.svg from scene_bench's JSON output.

    build/tests/bench/scene_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \\
        --benchmark_out=scene_bench.json --benchmark_out_format=json
    scripts/plot_scene_bench.py scene_bench.json docs/img/scene_tick_costs.svg

Bars: the median time per tick; whiskers: p50 to p99 of 20,000 individually timed ticks (each
includes a clock read of about 30 ns). The issue's targets are drawn where they apply.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

LABELS = {
    "empty": "empty scene",
    "one_wall": "one wall",
    "default_server": "default scene\n(wall + spring)",
    "mixed_10_objects_3_fields": "10 mixed objects\n+ 3 fields",
    "users_8x10_objects": "8 users ×\n10 objects",
    "mesh_10k_triangles": "10k-triangle\nmesh",
    "spheres_1000": "1,000 spheres",
    "spheres_1000_every_sphere": "1,000 spheres,\nno broad phase",
    "spheres_10648": "10,648 spheres",
    "spheres_10648_every_sphere": "10,648 spheres,\nno broad phase",
}
TARGETS_NS = {"mixed_10_objects_3_fields": 2000.0, "spheres_1000": 1000.0, "spheres_10648": 2000.0,
              "mesh_10k_triangles": 20000.0}


def main(source, target):
    with open(source) as f:
        data = json.load(f)
    rows = []
    for bench in data["benchmarks"]:
        if bench.get("aggregate_name") != "median":
            continue
        key = bench["name"].split("/")[1].rsplit("_median", 1)[0]
        rows.append((key, bench["cpu_time"], bench["p50_ns"], bench["p99_ns"]))
    order = list(LABELS)
    rows.sort(key=lambda r: order.index(r[0]) if r[0] in order else len(order))
    names = [LABELS.get(r[0], r[0]) for r in rows]
    fig, ax = plt.subplots(figsize=(10.5, 4.4))
    x = range(len(rows))
    ax.bar(x, [r[1] for r in rows], color="#4c72b0", label="median per tick")
    ax.vlines(x, [r[2] for r in rows], [r[3] for r in rows], color="black", lw=1.2,
              label="p50 … p99 of single ticks")
    for i, r in enumerate(rows):
        if r[0] in TARGETS_NS:
            ax.hlines(TARGETS_NS[r[0]], i - 0.4, i + 0.4, color="#c44e52", lw=2,
                      label="target" if r[0] == "mixed_10_objects_3_fields" else None)
    ax.set_yscale("log")
    ax.set_ylabel("evaluate_scene per tick [ns]")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, fontsize=7)
    ax.set_title("Scene cost per 1 ms tick (2-core VM, scene_bench)")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(target)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
