#!/usr/bin/env bash
# ROS 2 bags as input. A synthetic sequence written as bags (MCAP with zstd / lz4
# chunks, SQLite; raw and compressed images; the pose only as a TF chain) gives the same
# scene through `semrec run` as the folder it was written from; `semrec info` lists the topics,
# the chosen ones and the TF chain; bad bags are clear errors.
set -u
SEMREC="$1"
MAKE_BAG="$2"
fail() { echo "FAIL: $*"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$SEMREC" synth --preset six-objects --frames 8 --out "$tmp/syn" >/dev/null || fail "synth failed"
# Depth as 32FC1 metres: exactly the folder's depth (synth stores 1/5000 m).
"$MAKE_BAG" "$tmp/syn" "$tmp/zstd" --float-depth || fail "writing the zstd bag failed"
"$MAKE_BAG" "$tmp/syn" "$tmp/lz4.mcap" --compression lz4 --bare --float-depth || fail "writing the lz4 bag failed"
"$MAKE_BAG" "$tmp/syn" "$tmp/sqlite" --storage sqlite3 --float-depth || fail "writing the SQLite bag failed"

"$SEMREC" info "$tmp/zstd" >"$tmp/info.txt" 2>&1 || fail "info on the bag failed: $(tail -3 "$tmp/info.txt")"
for want in "rosbag2 (mcap)" "/camera/color/image_raw" "sensor_msgs/msg/CameraInfo" \
  "TF map -> odom -> base_link -> camera_link -> camera_color_optical_frame" \
  "frames: 8 of 8 colour images paired" "zstd chunk" "read by a linear scan"; do
  grep -qF "$want" "$tmp/info.txt" || { cat "$tmp/info.txt"; fail "info does not say '$want'"; }
done

# Labels for the bag's frames: the synthetic ground truth under the bag's frame names.
labels="$tmp/labels"; mkdir -p "$labels/semantic" "$labels/instance"
cp "$tmp/syn/gt/classes.json" "$labels/"
i=0
for f in $(ls "$tmp/syn/semantic" | sort); do
  name="$(printf 'frame-%06d.depth.png' "$i")"
  cp "$tmp/syn/semantic/$f" "$labels/semantic/$name"
  cp "$tmp/syn/instance/$f" "$labels/instance/$name"
  i=$((i + 1))
done

"$SEMREC" mesh "$tmp/syn" --labels gt --out "$tmp/folder_out" --no-ply >"$tmp/folder.log" 2>&1 ||
  fail "mesh on the folder failed: $(tail -3 "$tmp/folder.log")"
for bag in zstd lz4.mcap sqlite; do
  "$SEMREC" mesh "$tmp/$bag" --labels "$labels" --out "$tmp/out_$bag" --no-ply >"$tmp/$bag.log" 2>&1 ||
    fail "mesh on the $bag bag failed: $(tail -3 "$tmp/$bag.log")"
  python3 - "$tmp/folder_out/report.json" "$tmp/out_$bag/report.json" <<'PY' || fail "the $bag bag gives another scene"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
def objs(j):
    # The same depth, poses to 1e-9 and labels: the same fused points and meshes.
    return sorted((o["id"], o["class"], o["fused_points"], o["vertices"], o["triangles"])
                  for o in j["scene"])
oa, ob = objs(a), objs(b)
if oa != ob:
    print("folder:", oa); print("bag:   ", ob); sys.exit(1)
print(f"{len(oa)} objects alike")
PY
done

same_mesh() {  # folder.ply bag.ply: same vertex count (> 1000), each within 1 mm
  python3 - "$1" "$2" <<'PY'
import struct, sys
def vertices(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
    props, in_vertex = [], False
    for l in header:
        if l.startswith("element"):
            in_vertex = l.startswith("element vertex")
        elif l.startswith("property") and in_vertex:
            props.append(l.split()[1])
    sizes = {"float": 4, "double": 8, "uchar": 1, "uint8": 1}
    fmt = "<" + "".join({"float": "f", "double": "d", "uchar": "B", "uint8": "B"}[p] for p in props)
    stride = sum(sizes[p] for p in props)
    return [struct.unpack_from(fmt, data, end + i * stride)[:3] for i in range(n)]
a, b = vertices(sys.argv[1]), vertices(sys.argv[2])
worst = max((max(abs(x - y) for x, y in zip(p, q)) for p, q in zip(a, b)), default=0.0)
print(f"{len(a)} vs {len(b)} vertices, largest difference {worst * 1000:.6f} mm")
sys.exit(0 if len(a) == len(b) and len(a) > 1000 and worst < 1e-3 else 1)
PY
}

# Real frames (7-Scenes chess, depth in mm as the bag stores it): the same TSDF mesh from the bag
# (MCAP and SQLite) and from the folder, vertex for vertex within 1 mm.
chess="$SEMREC_SOURCE_DIR/../shared/data/7scenes_chess_0_99"
if [ -d "$chess" ]; then
  "$MAKE_BAG" "$chess" "$tmp/chess" --max-frames 3 || fail "writing the chess bag failed"
  "$MAKE_BAG" "$chess" "$tmp/chess.db3" --max-frames 3 --storage sqlite3 --bare ||
    fail "writing the chess SQLite bag failed"
  "$SEMREC" tsdf "$chess" --max-frames 3 --voxel-size-m 0.02 -o "$tmp/chess_folder.ply" >/dev/null 2>&1 ||
    fail "tsdf on the chess folder failed"
  for bag in chess chess.db3; do
    "$SEMREC" tsdf "$tmp/$bag" --voxel-size-m 0.02 -o "$tmp/$bag.ply" >/dev/null 2>&1 ||
      fail "tsdf on the $bag bag failed"
    same_mesh "$tmp/chess_folder.ply" "$tmp/$bag.ply" || fail "the $bag bag gives another mesh"
  done
else
  missing_chess=1
fi
# Bonn (TUM layout, depth in 1/5000 m, mocap poses corrected): as 32FC1 depth, the same mesh too.
bonn="$SEMREC_SOURCE_DIR/../shared/data/bonn_crowd_150"
if [ -d "$bonn" ] && [ -z "${missing_chess:-}" ]; then
  corr=(--pose-correction "$SEMREC_SOURCE_DIR/data/poses/bonn_rgbd_dynamic.yaml")
  "$SEMREC" tsdf "$bonn" "${corr[@]}" --max-frames 3 --voxel-size-m 0.03 -o "$tmp/bonn_folder.ply" \
    >/dev/null 2>&1 || fail "tsdf on the Bonn folder failed"
  "$MAKE_BAG" "$bonn" "$tmp/bonn" --max-frames 3 --float-depth --pose-correction \
    "$SEMREC_SOURCE_DIR/data/poses/bonn_rgbd_dynamic.yaml" || fail "writing the Bonn bag failed"
  "$SEMREC" tsdf "$tmp/bonn" --voxel-size-m 0.03 -o "$tmp/bonn_bag.ply" >/dev/null 2>&1 ||
    fail "tsdf on the Bonn bag failed"
  same_mesh "$tmp/bonn_folder.ply" "$tmp/bonn_bag.ply" || fail "the Bonn bag gives another mesh"
fi

# Bad input: not a bag, a damaged one, a missing topic.
printf 'not a bag' >"$tmp/x.mcap"
"$SEMREC" info "$tmp/x.mcap" >"$tmp/bad.txt" 2>&1 && fail "info accepted a file that is not MCAP"
grep -q "x.mcap: not an MCAP file" "$tmp/bad.txt" || { cat "$tmp/bad.txt"; fail "unclear error for a non-MCAP file"; }
"$SEMREC" info "$tmp/zstd" --depth-topic /nope >"$tmp/bad.txt" 2>&1 && fail "info accepted a missing topic"
grep -q "no topic '/nope'" "$tmp/bad.txt" || { cat "$tmp/bad.txt"; fail "unclear error for a missing topic"; }
echo "bags: ok"
# Reported as skipped (a failure in CI) when the real frames were missing.
[ -z "${missing_chess:-}" ] || { echo "SKIP: no 7-Scenes sample data at $chess"; exit 77; }
