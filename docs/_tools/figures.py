"""The figures of docs/guarantee.md, drawn with matplotlib as SVG when the site is built.

    python figures.py OUT_DIR

Each is a 2D cut through the 3D tests, to scale: what a query shape is for each mode (VT: the
vertex's box or sphere of radius r; EE: the edge's box or capsule), how a node's box is tested
against such a shape, and the box of a swept element. The SVGs carry no date or random ids, so
a rebuild writes the same bytes.
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle, Polygon, Rectangle  # noqa: E402

plt.rcParams.update({"svg.hashsalt": "minkq", "font.size": 9, "svg.fonttype": "none"})
SHAPE, ELEMENT, BOX, HIT = "#1f77b4", "#444444", "#ff7f0e", "#2ca02c"


def _panel(ax, title):
    ax.set_title(title)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def _save(fig, out: Path, name: str):
    """Writes the figure as out/name.svg, without a date, and frees it."""
    fig.tight_layout()
    fig.savefig(out / f"{name}.svg", metadata={"Date": None})
    plt.close(fig)


def _capsule(ax, a, b, r, **style):
    """A 2D capsule: the points within r of segment ab."""
    import numpy as np

    a, b = np.asarray(a, float), np.asarray(b, float)
    d = (b - a) / np.linalg.norm(b - a)
    n = np.array([-d[1], d[0]])
    t = np.linspace(0, np.pi, 24)
    cap_b = [b + r * (np.cos(s) * -n + np.sin(s) * d) for s in t]
    cap_a = [a + r * (np.cos(s) * n - np.sin(s) * d) for s in t]
    ax.add_patch(Polygon(cap_b + cap_a, closed=True, fill=False, **style))


def modes(out: Path):
    """VT: box / sphere around the vertex against the triangle; EE: box / capsule of an edge."""
    fig, axes = plt.subplots(1, 3, figsize=(9, 3.2))
    tri = [(0, 0), (2, 0), (1, 1.4)]
    r, p = 0.5, (2.4, 1.8)
    for ax, title, shape in ((axes[0], "VT, mode box", "box"), (axes[1], "VT, mode sphere", "sphere")):
        _panel(ax, title)
        ax.add_patch(Polygon(tri, closed=True, color=ELEMENT, alpha=0.25))
        ax.add_patch(Rectangle((0, 0), 2, 1.4, fill=False, ls="--", color=BOX, label="triangle's box"))
        if shape == "box":
            ax.add_patch(Rectangle((p[0] - r, p[1] - r), 2 * r, 2 * r, fill=False, color=SHAPE, label="query box (r)"))
            ax.text(0.05, 2.35, "boxes overlap: candidate", color=BOX)
        else:
            ax.add_patch(Circle(p, r, fill=False, color=SHAPE, label="sphere (r)"))
            ax.text(0.05, 2.35, "sphere misses the box: dropped", color=SHAPE)
        ax.plot(*p, "o", color=ELEMENT)
        ax.set(xlim=(-0.3, 3.1), ylim=(-0.3, 2.5))
    ax = axes[2]
    _panel(ax, "EE, box and capsule_exact")
    e, f = ((0, 0), (2, 1)), ((-0.5, 0.9), (0.6, 1.8))
    r = 0.35
    ax.plot(*zip(*e), color=ELEMENT, lw=2)
    ax.plot(*zip(*f), color=ELEMENT, lw=2)
    ax.add_patch(Rectangle((-r, -r), 2 + 2 * r, 1 + 2 * r, fill=False, color=BOX, ls="--", label="edge's box + r"))
    _capsule(ax, *e, r, color=SHAPE)
    ax.text(-0.3, 2.05, "f crosses the box, misses the capsule", color=SHAPE)
    ax.set(xlim=(-0.6, 3.0), ylim=(-0.6, 2.3))
    _save(fig, out, "modes")


def node_tests(out: Path):
    """A node's box against the query: overlap of boxes (box) or distance to the box (sphere)."""
    fig, ax = plt.subplots(figsize=(5, 3.2))
    _panel(ax, "node tests: the box of a subtree against the query")
    ax.add_patch(Rectangle((0, 0), 2.5, 1.5, fill=False, color=BOX, lw=1.5))
    ax.text(0.1, 1.3, "node box", color=BOX)
    for x, y, hit_box, hit_sphere in ((3.0, 2.0, True, False), (3.0, 0.8, True, True)):
        r = 0.6
        ax.add_patch(Rectangle((x - r, y - r), 2 * r, 2 * r, fill=False, color=SHAPE, ls=":"))
        ax.add_patch(Circle((x, y), r, fill=False, color=SHAPE))
        ax.plot(x, y, "o", color=ELEMENT)
        verdict = ("box: visit" if hit_box else "box: skip") + (", sphere: visit" if hit_sphere else ", sphere: skip")
        ax.text(x + 0.65, y, verdict, va="center")
    ax.set(xlim=(-0.3, 6.3), ylim=(-0.3, 2.7))
    _save(fig, out, "node_tests")


def swept(out: Path):
    """A vertex moving from x0 to x1 and an edge moving over the step: their swept boxes."""
    fig, ax = plt.subplots(figsize=(6, 3.2))
    _panel(ax, "swept queries: every position of the step, widened by r")
    r = 0.25
    x0, x1 = (0.3, 2.0), (1.6, 0.4)
    ax.annotate("", xy=x1, xytext=x0, arrowprops={"arrowstyle": "->", "color": ELEMENT})
    ax.plot(*zip(x0, x1), "o", color=ELEMENT)
    ax.text(x0[0] - 0.25, x0[1] + 0.15, "x0")
    ax.text(x1[0] + 0.05, x1[1] - 0.3, "x1")
    ax.add_patch(Rectangle((x0[0] - r, x1[1] - r), x1[0] - x0[0] + 2 * r, x0[1] - x1[1] + 2 * r, fill=False, color=BOX))
    _capsule(ax, x0, x1, r, color=SHAPE)
    ax.text(-0.1, -0.25, "VT: the path's box (box) or capsule", color=SHAPE)
    e0, e1 = ((2.6, 0.3), (3.6, 0.6)), ((2.9, 1.6), (3.9, 2.1))
    for e, style in ((e0, "-"), (e1, "--")):
        ax.plot(*zip(*e), color=ELEMENT, lw=2, ls=style)
    xs = [p[0] for p in e0 + e1]
    ys = [p[1] for p in e0 + e1]
    ax.add_patch(Rectangle((min(xs), min(ys)), max(xs) - min(xs), max(ys) - min(ys), fill=False, color=BOX))
    ax.text(2.5, 2.3, "EE: the box over both positions", color=BOX)
    ax.set(xlim=(-0.3, 4.3), ylim=(-0.5, 2.5))
    _save(fig, out, "swept")


if __name__ == "__main__":
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    for draw in (modes, node_tests, swept):
        draw(out)
