#!/usr/bin/python3
"""Fuses a sequence with semrec and plots the objects from above, coloured by class (matplotlib).

    build/semrec synth --preset office --frames 30 --out /tmp/office
    PYTHONPATH=build/python examples/python/plot_classes.py /tmp/office --labels gt --png top.png
"""
import argparse
import sys

import numpy as np

import semrec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sequence")
    ap.add_argument("--labels", help="'gt' or a label folder: skip the models")
    ap.add_argument("--stride", type=int, default=1)
    ap.add_argument("--png", default="classes_top.png")
    args = ap.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("this example needs matplotlib (Debian: apt install python3-matplotlib)")

    seq = semrec.open_sequence(args.sequence, stride=args.stride, labels=args.labels)
    if args.labels:
        pipe = semrec.Pipeline(models=None, classes=f"{args.sequence}/gt/classes.json")
    else:
        pipe = semrec.Pipeline()
    for f in seq:
        labels = dict(semantic=f.semantic, instance=f.instance) if args.labels else {}
        pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera, **labels)
    pipe.finish()

    fig, ax = plt.subplots(figsize=(8, 8))
    classes = sorted({o["class"] for o in pipe.objects()})
    cmap = plt.get_cmap("tab20")
    for o in sorted(pipe.objects(), key=lambda o: o["kind"] != "stuff"):  # structure below
        p = o["points"]
        if len(p) == 0:
            continue
        c = cmap(classes.index(o["class"]) % 20)
        ax.scatter(p[:, 0], p[:, 1], s=1, color=c, alpha=0.3 if o["kind"] == "stuff" else 0.9)
        if o["kind"] != "stuff":
            ax.annotate(f"{o['class']} {o['id']}", p.mean(axis=0)[:2], fontsize=7)
    for name in classes:
        ax.scatter([], [], color=cmap(classes.index(name) % 20), label=name)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper right", fontsize=7, markerscale=4)
    fig.savefig(args.png, dpi=120)
    print("wrote", args.png, f"({len(pipe.objects())} objects, classes: {', '.join(classes)})")


if __name__ == "__main__":
    main()
