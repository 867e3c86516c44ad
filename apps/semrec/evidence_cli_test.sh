#!/usr/bin/env bash
# On segmenter-like labels (synth --label-noise), fusion with multi-view evidence
# brings the object count and instance AP50 close to the ground-truth labels' (the oracle),
# while the paper's rule alone writes several objects per real one.
set -u
SEMREC="$1"
fail() { echo "FAIL: $*"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$SEMREC" synth --preset six-objects --frames 30 --label-noise --out "$tmp/syn" >/dev/null ||
  fail "synth --label-noise failed"
[ -f "$tmp/syn/labels_noisy/classes.json" ] && [ -f "$tmp/syn/labels_noisy/instance/000029.png" ] ||
  fail "synth --label-noise: no labels_noisy folder"
score() {  # labels merge -> prints "objects ap50 miou"
  "$SEMREC" mesh "$tmp/syn" --labels "$1" --merge "$2" --out "$tmp/$2_$3" --no-ply >/dev/null 2>&1 ||
    fail "mesh --labels $1 --merge $2 failed"
  "$SEMREC" eval scene "$tmp/$2_$3" "$tmp/syn/gt/surface_points.ply" --observed-in "$tmp/syn" --json \
    2>/dev/null >"$tmp/$2_$3.json" || fail "eval scene ($2, $3) failed"
  python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['predicted_objects'], j['ap50'], j['mean_iou'])" \
    "$tmp/$2_$3.json"
}
read -r oracle_n oracle_ap oracle_miou <<<"$(score gt evidence oracle)"
read -r paper_n paper_ap paper_miou <<<"$(score "$tmp/syn/labels_noisy" paper noisy)"
read -r ev_n ev_ap ev_miou <<<"$(score "$tmp/syn/labels_noisy" evidence noisy)"
echo "objects / AP50 / mIoU: oracle $oracle_n $oracle_ap $oracle_miou; paper $paper_n $paper_ap $paper_miou;" \
  "evidence $ev_n $ev_ap $ev_miou"
python3 - "$oracle_n" "$oracle_ap" "$paper_n" "$paper_ap" "$ev_n" "$ev_ap" "$ev_miou" "$paper_miou" <<'PY' ||
import sys
on, oap, pn, pap, en, eap, emiou, pmiou = map(float, sys.argv[1:])
ok = on == 6 and oap > 0.95            # the oracle finds the six objects
ok &= pn >= 3 * on                     # the paper's rule: several objects per object
ok &= en <= 1.5 * on and eap >= oap - 0.2 and eap >= pap + 0.2 and emiou > pmiou + 0.1
sys.exit(0 if ok else 1)
PY
  fail "evidence merging does not recover the objects"
grep -q '"event": "evidence_merge"' "$tmp/evidence_noisy/report.json" || fail "report.json lists no evidence merge"
grep -q '"class_votes"' "$tmp/evidence_noisy/report.json" || fail "report.json has no class votes"
grep -q 'semrec:classVotes' "$tmp/evidence_noisy/static.usda" || fail "USD has no class votes"
"$SEMREC" mesh "$tmp/syn" --merge magic --out "$tmp/bad" 2>"$tmp/err"; rc=$?
[ "$rc" -ne 0 ] && grep -q "magic" "$tmp/err" || fail "--merge magic accepted: $(cat "$tmp/err")"
echo "ok"
