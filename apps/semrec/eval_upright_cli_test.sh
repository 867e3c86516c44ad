#!/usr/bin/env bash
# `semrec eval scene` scores a result that `semrec run` turned upright in the result's
# frame, taking T_upright_world from the scene's customLayerData. A synthetic recording with its
# world tilted (poses and ground truth) scores like the untilted one, and badly with the identity
# in place of the transform; a missing or malformed entry is an error naming the file.
set -u
SEMREC="$1"
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
tmp="${KEEP_TMP:-$(mktemp -d)}"; mkdir -p "$tmp"; trap '[ -n "${KEEP_TMP:-}" ] || rm -rf "$tmp"' EXIT

# 8 frames, not 6: the sofa at the edge of the views then has ~40 map voxels in either frame (at 6,
# 21 untilted and under the 20-voxel fragment bound tilted: the grids differ, and one class more
# or less moves this small scene's mIoU by 0.14).
"$SEMREC" synth --preset six-objects --frames 8 --width 160 --height 120 --gt-spacing-m 0.02 \
  --out "$tmp/syn" >/dev/null 2>"$tmp/err" || fail "synth: $(cat "$tmp/err")"
# The same recording in a tilted world: 36.87 degrees about x (cos 0.8, sin 0.6), shifted;
# camera poses and ground truth moved alike (then --observed-in works on either).
cp -r "$tmp/syn" "$tmp/tilt"
/usr/bin/python3 - "$tmp/syn" "$tmp/tilt" <<'PY' ||
import re, struct, sys
src, dst = sys.argv[1:3]
T = [[1, 0, 0, 0.4], [0, 0.8, -0.6, -0.3], [0, 0.6, 0.8, 1.2], [0, 0, 0, 1]]
def pose(m):  # T * (a row-major pose)
    a = [float(x) for x in m.group(1).split(",")]
    b = [sum(T[r][k] * a[4 * k + c] for k in range(4)) for r in range(4) for c in range(4)]
    return "T_world_camera: [" + ", ".join(repr(x) for x in b) + "]"
text = open(src + "/sequence.yaml").read()
open(dst + "/sequence.yaml", "w").write(re.sub(r"T_world_camera: \[([^\]]*)\]", pose, text))
# The ground truth: binary PLY, a vertex element only; x y z moved.
data = open(src + "/gt/surface_points.ply", "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
header = data[:end].decode().splitlines()
assert "format binary_little_endian 1.0" in header, header
codes = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
         "float": "f", "double": "d", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
         "int32": "i", "uint32": "I", "float32": "f", "float64": "d"}
elements = [l.split() for l in header if l.startswith("element")]
assert len(elements) == 1 and elements[0][1] == "vertex", elements
props = [l.split() for l in header if l.startswith("property")]
row = struct.Struct("<" + "".join(codes[p[1]] for p in props))
names = [p[2] for p in props]
xyz = [names.index(n) for n in "xyz"]
out = bytearray(data[:end])
for k in range(int(elements[0][2])):
    v = list(row.unpack_from(data, end + k * row.size))
    p = [v[i] for i in xyz] + [1]
    for r, i in enumerate(xyz):
        v[i] = sum(T[r][c] * p[c] for c in range(4))
    out += row.pack(*v)
open(dst + "/gt/surface_points.ply", "wb").write(out)
PY
  fail "could not tilt the recording"

run() {  # name sequence
  local name="$1" seq="$2"
  "$SEMREC" run "$tmp/$seq" --labels gt --no-people --no-overlays --no-ply --no-report \
    --out "$tmp/$name" >/dev/null 2>"$tmp/$name.err" || fail "run $name: $(tail -3 "$tmp/$name.err")"
}
miou() {  # result sequence -> prints mIoU on what the sequence saw
  "$SEMREC" eval scene "$tmp/$1" "$tmp/$2/gt/surface_points.ply" --observed-in "$tmp/$2" --json \
    >"$tmp/eval.json" 2>"$tmp/eval.err" ||
    fail "eval scene $1: $(cat "$tmp/eval.err")"
  /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['mean_iou'])" "$tmp/eval.json"
}
run flat syn
run tilted tilt
grep -q 'string gravity = "planes"\|string gravity = "floor class"' "$tmp/tilted/scene.usda" ||
  fail "the tilted run was not turned upright: $(grep gravity "$tmp/tilted/scene.usda")"
flat=$(miou flat syn)
tilted=$(miou tilted tilt)
# With the identity in place of the transform: scored in the wrong frame.
identity="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"
cp -r "$tmp/tilted" "$tmp/ident"
sed -i "s/string T_upright_world = \".*\"/string T_upright_world = \"$identity\"/" "$tmp/ident"/*.usda
wrong=$(miou ident tilt)
echo "mIoU: untilted $flat, tilted $tilted, tilted scored with the identity $wrong"
/usr/bin/python3 -c "import sys; f, t, w = map(float, sys.argv[1:]); sys.exit(0 if f > 0.6 and abs(t - f) < 0.05 and w < 0.2 else 1)" \
  "$flat" "$tilted" "$wrong" || fail "tilted scores: untilted $flat, tilted $tilted, identity $wrong"

# No entry: an error naming the scene, never the identity.
cp -r "$tmp/tilted" "$tmp/noentry"
sed -i '/string T_upright_world = /d' "$tmp/noentry"/*.usda
"$SEMREC" eval scene "$tmp/noentry" "$tmp/tilt/gt/surface_points.ply" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "noentry/scene.usda: the result was turned upright (gravity: [a-z ]*) but" "$tmp/err" ||
  fail "no transform: exit $rc $(cat "$tmp/err")"
# Malformed: an error naming the layer and the entry.
sed -i 's/string T_upright_world = ".*"/string T_upright_world = "1 0 0"/' "$tmp/ident/scene.usda"
"$SEMREC" eval scene "$tmp/ident" "$tmp/tilt/gt/surface_points.ply" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "ident/scene.usda: customLayerData T_upright_world is not 16 numbers" "$tmp/err" ||
  fail "malformed entry: exit $rc $(cat "$tmp/err")"
sed -i 's/string T_upright_world = ".*"/string T_upright_world = "2 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/' \
  "$tmp/ident/scene.usda"
"$SEMREC" eval scene "$tmp/ident" "$tmp/tilt/gt/surface_points.ply" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "ident/scene.usda: customLayerData T_upright_world: rotation block is not orthonormal" \
  "$tmp/err" || fail "non-rigid entry: exit $rc $(cat "$tmp/err")"
echo "ok"
