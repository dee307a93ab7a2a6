#!/usr/bin/env python3
"""Plots for bench/results from the CSV files the bench programs write (matplotlib, PNG).

  error_vs_time_<scene>.png  per scene: candidates / true contacts against query time and against
                             end-to-end time (query + measured narrow phase), VT and EE, every mode
  error_vs_time_all.png      the same for every reference scene on one page
  sweep_speed.png            speed of each mode over box against r / mean edge (radius sweep)

usage: plot.py RESULTS_DIR
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MODE_STYLE = {
    "box": ("o", "#444444"),
    "sphere": ("s", "#1f77b4"),
    "capsule_ray": ("^", "#ff7f0e"),
    "capsule_exact": ("D", "#2ca02c"),
    "leaf_exact": ("*", "#d62728"),
    "point_query+exact_leaf": ("P", "#9467bd"),
}
ORDER = {"VT": ["box", "sphere", "leaf_exact"], "EE": ["box", "capsule_ray", "capsule_exact", "leaf_exact"]}


def read(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def machine_line(results):
    path = os.path.join(results, "summary.md")
    if os.path.exists(path):
        for line in open(path):
            if line.startswith("Machine:"):
                return line.split(". TBB")[0].replace("Machine: ", "")
    return ""


def panel(ax, rows, kind, use_e2e, title):
    pts = [r for r in rows if r["kind"] == kind]
    xs, ys = [], []
    for mode in ORDER[kind]:
        for r in pts:
            if r["mode"] != mode:
                continue
            true = float(r["true_contacts"])
            cand = float(r["candidates"])
            y = cand / true if true > 0 else float("nan")
            x = float(r["end_to_end_ms"] if use_e2e else r["query_ms"])
            marker, color = MODE_STYLE[mode]
            ax.scatter([x], [y], marker=marker, color=color, s=70, label=mode, zorder=3)
            xs.append(x)
            ys.append(y)
    if len(xs) > 1:
        ax.plot(xs, ys, color="#999999", lw=0.8, zorder=1)
    ax.set_yscale("log")
    ax.set_xlabel(("end-to-end" if use_e2e else "query") + " time, ms (sum over frames)")
    ax.set_ylabel("candidates / true contacts")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)


def error_vs_time(results, machine):
    rows = [r for r in read(os.path.join(results, "error_vs_time.csv")) if r["suite"] == "scenes" and r["backend"] == "cpu"]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    for scene in scenes:
        sr = [r for r in rows if r["scene"] == scene]
        fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
        for i, kind in enumerate(["VT", "EE"]):
            panel(axes[i][0], sr, kind, False, f"{kind}: query only")
            panel(axes[i][1], sr, kind, True, f"{kind}: query + narrow phase")
        handles, labels = [], []
        for ax in axes.flat:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels:
                    handles.append(h)
                    labels.append(lab)
        fig.legend(handles, labels, loc="upper right", fontsize=8)
        fig.suptitle(f"{scene}: candidate excess against run time (cpu)\n{machine}", fontsize=9)
        fig.tight_layout(rect=(0, 0, 0.88, 0.95))
        out = os.path.join(results, f"error_vs_time_{scene}.png")
        fig.savefig(out, dpi=90)
        plt.close(fig)
        print("wrote", out)
    if scenes:
        cols = 3
        nrows = math.ceil(len(scenes) / cols)
        fig, axes = plt.subplots(nrows * 2, cols, figsize=(4 * cols, 3.0 * nrows * 2))
        for i, scene in enumerate(scenes):
            sr = [r for r in rows if r["scene"] == scene]
            for k, kind in enumerate(["VT", "EE"]):
                ax = axes[(i // cols) * 2 + k][i % cols]
                panel(ax, sr, kind, True, f"{scene} {kind}")
                ax.set_xlabel("end-to-end ms", fontsize=7)
                ax.set_ylabel("cand / true", fontsize=7)
                ax.tick_params(labelsize=6)
        for j in range(len(scenes), nrows * cols):
            for k in range(2):
                axes[(j // cols) * 2 + k][j % cols].axis("off")
        handles, labels = [], []
        for ax in axes.flat:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels:
                    handles.append(h)
                    labels.append(lab)
        fig.legend(handles, labels, loc="lower right", fontsize=9)
        fig.suptitle("Candidate excess against end-to-end time, every reference scene (cpu)\n" + machine, fontsize=10)
        fig.tight_layout(rect=(0, 0, 1, 0.97))
        out = os.path.join(results, "error_vs_time_all.png")
        fig.savefig(out, dpi=80)
        plt.close(fig)
        print("wrote", out)


def sweep(results, machine):
    rows = [r for r in read(os.path.join(results, "rows.csv")) if r["suite"] == "sweep" and r["backend"] == "cpu"]
    if not rows:
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    scenes = []
    for r in rows:
        base = r["scene"].split("@")[0]
        if base not in scenes:
            scenes.append(base)
    for k, (kind, mode) in enumerate([("VT", "sphere"), ("EE", "capsule_exact")]):
        ax = axes[k]
        for scene in scenes:
            pts = []
            for r in rows:
                if r["scene"].split("@")[0] != scene or r["kind"] != kind or r["mode"] != mode:
                    continue
                box = [b for b in rows if b["scene"] == r["scene"] and b["kind"] == kind and b["mode"] == "box"]
                if box:
                    pts.append((float(r["radius_factor"]), float(box[0]["ms_median"]) / float(r["ms_median"])))
            pts.sort()
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, label=scene)
        ax.axhline(1, color="k", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("r / mean edge")
        ax.set_ylabel(f"{kind} {mode} speed over box")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=6)
    fig.suptitle("Radius sweep (cpu, last frame)\n" + machine, fontsize=9)
    fig.tight_layout()
    out = os.path.join(results, "sweep_speed.png")
    fig.savefig(out, dpi=90)
    plt.close(fig)
    print("wrote", out)


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    results = sys.argv[1]
    machine = machine_line(results)
    error_vs_time(results, machine)
    sweep(results, machine)
    return 0


if __name__ == "__main__":
    sys.exit(main())
