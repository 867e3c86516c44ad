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
    objects = pipe.objects()
    things = sorted({o["class"] for o in objects if o["kind"] != "stuff"})
    stuff = sorted({o["class"] for o in objects if o["kind"] == "stuff"})
    # Structure in greys underneath, things in distinct colours on top.
    colour = {name: plt.get_cmap("tab10")(i % 10) for i, name in enumerate(things)}
    colour.update({name: str(0.55 + 0.3 * i / max(1, len(stuff))) for i, name in enumerate(stuff)})
    for o in sorted(objects, key=lambda o: o["kind"] != "stuff"):
        p = o["points"]
        if len(p) == 0:
            continue
        ax.scatter(p[:, 0], p[:, 1], s=2, color=colour[o["class"]], linewidths=0)
        if o["kind"] != "stuff":
            ax.annotate(f"{o['class']} {o['id']}", p.mean(axis=0)[:2], fontsize=7)
    handles = [plt.Line2D([], [], marker="o", linestyle="", color=colour[n], label=n)
               for n in stuff + things]
    ax.legend(handles=handles, loc="upper right", fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.savefig(args.png, dpi=120)
    print("wrote", args.png, f"({len(objects)} objects; classes: {', '.join(stuff + things)})")


if __name__ == "__main__":
    main()
