#!/usr/bin/env bash
# Objects decided per map voxel (--merge voxel, the default) on the failures real
# walk-throughs show: sparse independent views (objects seen once or twice) and labels that
# bleed into the floor and walls, correlated across views. With ground-truth labels the default
# is no worse than the paper's rule; with noisy, bleeding labels it beats it by a wide margin
# and stays close to the oracle; no object is dropped for being seen in one view.
set -u
SEMREC="$1"
fail() { echo "FAIL: $*"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$SEMREC" synth --preset six-objects --views sparse --frames 16 --label-noise --label-bleed \
  --out "$tmp/syn" >/dev/null || fail "synth --views sparse --label-bleed failed"
score() {  # labels merge tag -> prints "objects gt_objects ap50 miou"
  "$SEMREC" mesh "$tmp/syn" --labels "$1" --merge "$2" --out "$tmp/$3" --no-ply >"$tmp/$3.log" 2>&1 ||
    fail "mesh --labels $1 --merge $2 failed: $(tail -3 "$tmp/$3.log")"
  "$SEMREC" eval scene "$tmp/$3" "$tmp/syn/gt/surface_points.ply" --observed-in "$tmp/syn" --json \
    2>/dev/null >"$tmp/$3.json" || fail "eval scene ($3) failed"
  python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['predicted_objects'], j['gt_objects'], j['ap50'], j['mean_iou'])" \
    "$tmp/$3.json"
}
read -r gp_n gt_n gp_ap gp_miou <<<"$(score gt paper gt_paper)"
read -r gv_n _ gv_ap gv_miou <<<"$(score gt voxel gt_voxel)"
read -r np_n _ np_ap np_miou <<<"$(score "$tmp/syn/labels_noisy" paper noisy_paper)"
read -r nv_n _ nv_ap nv_miou <<<"$(score "$tmp/syn/labels_noisy" voxel noisy_voxel)"
echo "objects / AP50 / mIoU (GT objects $gt_n): gt paper $gp_n $gp_ap $gp_miou; gt voxel $gv_n $gv_ap $gv_miou;" \
  "noisy paper $np_n $np_ap $np_miou; noisy voxel $nv_n $nv_ap $nv_miou"
python3 - "$gt_n" "$gp_n" "$gp_ap" "$gp_miou" "$gv_n" "$gv_ap" "$gv_miou" "$np_n" "$np_ap" "$np_miou" \
  "$nv_n" "$nv_ap" "$nv_miou" <<'PY' ||
import sys
gt, gpn, gpap, gpm, gvn, gvap, gvm, npn, npap, npm, nvn, nvap, nvm = map(float, sys.argv[1:])
ok = gvap >= gpap - 1e-9 and gvm >= gpm - 0.01             # oracle: no worse than the paper rule
ok &= abs(gvn - gt) <= abs(gpn - gt)                         # ... and no farther from the GT count
ok &= nvap >= npap + 0.2 and nvm >= npm + 0.05               # noisy: a wide margin over the paper
ok &= nvap >= gvap - 0.25 and nvm >= gvm - 0.1               # ... and close to the oracle
sys.exit(0 if ok else 1)
PY
  fail "voxel rule does not hold up on sparse views with bleeding labels"
python3 - "$tmp/gt_voxel.json" <<'PY' ||
import json, sys
views = [o["views"] for o in json.load(open(sys.argv[1]))["objects"]]
# --observed-in: each scored object was seen by 1-16 frames; sparse views see some once or twice.
sys.exit(0 if views and all(1 <= v <= 16 for v in views) and min(views) <= 2 else 1)
PY
  fail "eval scene --observed-in does not count the views of each ground-truth object"
grep -q "the map's objects: " "$tmp/gt_voxel.log" || fail "no per-voxel decision logged"
grep -q '"merge": "voxel"\|merge voxel' "$tmp/gt_voxel/report.json" "$tmp/gt_voxel/static.usda" ||
  fail "the result does not name the voxel rule"
python3 - "$tmp/gt_voxel/report.json" "$tmp/gt_paper/report.json" <<'PY' ||
import json, sys
v, p = (json.load(open(f)) for f in sys.argv[1:])
m = v["map_objects"]
ok = m["objects"] >= 1 and any(x["class"] == "floor" and x["geometry"] == "floor" for x in m["planes"])
ok &= len(m["visibility"]) >= 1 and all(0.3 <= o["seen_ratio"] <= 1 and o["max_views"] >= 1
                                        for o in m["visibility"])  # kept objects pass the rule
ok &= p["map_objects"] is None  # only the voxel rule decides per voxel
sys.exit(0 if ok else 1)
PY
  fail "report.json does not report the per-voxel decision (map_objects)"
# Surface patches: map voxels of things no volume meshed get one each (4 triangles), unless off.
"$SEMREC" mesh "$tmp/syn" --labels "$tmp/syn/labels_noisy" --no-surface-patches --out "$tmp/bare" \
  --no-ply >/dev/null 2>&1 || fail "mesh --no-surface-patches failed"
python3 - "$tmp/noisy_voxel/report.json" "$tmp/bare/report.json" <<'PY' ||
import json, sys
with_, bare = (json.load(open(f)) for f in sys.argv[1:])
tris = lambda j: sum(o["triangles"] for o in j["scene"])
n = with_["surface_patches"]
sys.exit(0 if n > 0 and bare["surface_patches"] == 0 and tris(with_) - tris(bare) == 4 * n else 1)
PY
  fail "surface patches: not counted in report.json, or --no-surface-patches does not turn them off"
echo "ok"
