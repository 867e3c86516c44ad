#!/usr/bin/python3
"""A camera loop feeding semrec frame by frame; prints objects as they appear.

A folder of RGB-D frames stands in for the camera (any layout semrec reads). With --labels gt the
frames' own labels are used (no models; e.g. a `semrec synth` sequence), otherwise the default
models run.

    PYTHONPATH=build/python examples/python/live_loop.py ../shared/data/7scenes_chess_0_99 --stride 10
    build/semrec synth --preset six-objects --frames 20 --out /tmp/syn
    PYTHONPATH=build/python examples/python/live_loop.py /tmp/syn --labels gt --out /tmp/syn_out
"""
import argparse
import time

import semrec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sequence")
    ap.add_argument("--labels", help="'gt' or a label folder: skip the models")
    ap.add_argument("--classes", help="label set of --labels (default: <sequence>/gt/classes.json)")
    ap.add_argument("--stride", type=int, default=1)
    ap.add_argument("--out", help="write the scene here at the end")
    args = ap.parse_args()

    seq = semrec.open_sequence(args.sequence, stride=args.stride, labels=args.labels)
    if args.labels:
        pipe = semrec.Pipeline(models=None,
                               classes=args.classes or f"{args.sequence}/gt/classes.json")
    else:
        pipe = semrec.Pipeline()
    seen = set()
    for frame in seq:  # the "camera"
        t = time.perf_counter()
        labels = dict(semantic=frame.semantic, instance=frame.instance) if args.labels else {}
        pipe.add_frame(frame.color, frame.depth, frame.K, frame.T_world_camera,
                       timestamp=frame.timestamp, **labels)
        new = [o for o in pipe.objects() if o["id"] not in seen]
        for o in new:
            seen.add(o["id"])
            centre = o["points"].mean(axis=0) if len(o["points"]) else [float("nan")] * 3
            print(f"frame {frame.index:4d}: new {o['class']} #{o['id']} "
                  f"({len(o['points'])} points, at {centre[0]:.2f} {centre[1]:.2f} {centre[2]:.2f} m)")
        print(f"frame {frame.index:4d}: {time.perf_counter() - t:.2f} s, "
              f"{len(pipe.objects())} objects so far", flush=True)
    pipe.finish()
    final = pipe.objects()
    print(f"final: {len(final)} objects: " +
          ", ".join(sorted(f"{o['class']} #{o['id']}" for o in final)))
    if args.out:
        print("wrote", pipe.write(args.out)["scene"])


if __name__ == "__main__":
    main()
