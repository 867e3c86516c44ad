// semrec's MCAP and CDR code against the reference implementations
// (@mcap/core, @foxglove/rosmsg2-serialization, @foxglove/rosmsg; pinned in
// scripts/setup). Both ways:
//  1. A bag written by @mcap/core (chunks, message indexes, summary,
//     statistics) with messages serialized by rosmsg2-serialization from the
//     ROS 2 .msg definitions is read by `semrec info`: frames, intrinsics,
//     depth range and trajectory length as written.
//  2. A bag written by semrec (semrec_make_test_bag) is read by
//     McapStreamReader with CRC checks, and every message decodes with the
//     schema text semrec stored, with the values semrec meant.
//   node bag_crosscheck_test.mjs SEMREC MAKE_TEST_BAG
import { execFileSync } from "node:child_process";
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const root = process.env.SEMREC_SOURCE_DIR ?? path.resolve(here, "../..");
const require = createRequire(path.join(root, ".deps/node/package.json"));
let mcap, rosmsg, serialization;
try {
  mcap = require("@mcap/core");
  rosmsg = require("@foxglove/rosmsg");
  serialization = require("@foxglove/rosmsg2-serialization");
} catch (e) {
  console.log(`SKIP: npm packages missing (run scripts/setup): ${e.message}`);
  process.exit(77);
}
const [semrec, makeBag] = process.argv.slice(2);
const fail = (msg) => {
  console.error(`FAIL: ${msg}`);
  process.exit(1);
};
const tmp = mkdtempSync(path.join(tmpdir(), "semrec-bag-"));
process.on("exit", () => rmSync(tmp, { recursive: true, force: true }));

const SEP = "=".repeat(80);
const TIME = "int32 sec\nuint32 nanosec\n";
const HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n";
const deps = (...blocks) => blocks.map(([n, t]) => `${SEP}\nMSG: ${n}\n${t}`).join("");
const DEFS = {
  "sensor_msgs/msg/Image":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n" +
    "uint32 step\nuint8[] data\n" + deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME]),
  "sensor_msgs/msg/CameraInfo":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n" +
    "float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n" +
    "RegionOfInterest roi\n" +
    deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME],
      ["sensor_msgs/RegionOfInterest",
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"]),
  "tf2_msgs/msg/TFMessage":
    "geometry_msgs/TransformStamped[] transforms\n" +
    deps(["geometry_msgs/TransformStamped",
      "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"],
    ["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME],
    ["geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"],
    ["geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"],
    ["geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"]),
};
const writerFor = (text) => new serialization.MessageWriter(rosmsg.parse(text, { ros2: true }));
const readerFor = (text) => new serialization.MessageReader(rosmsg.parse(text, { ros2: true }));

// --- 1. @mcap/core + rosmsg2-serialization write, semrec reads -------------------------------
{
  const W = 8, H = 6, FX = 7;
  const buffer = new mcap.TempBuffer();
  const writer = new mcap.McapWriter({ writable: buffer, chunkSize: 512 });
  await writer.start({ profile: "ros2", library: "crosscheck" });
  const channels = {};
  for (const [topic, type] of [["/tf_static", "tf2_msgs/msg/TFMessage"],
    ["/tf", "tf2_msgs/msg/TFMessage"], ["/cam/color/camera_info", "sensor_msgs/msg/CameraInfo"],
    ["/cam/color/image_raw", "sensor_msgs/msg/Image"],
    ["/cam/depth/image_raw", "sensor_msgs/msg/Image"]]) {
    const schemaId = await writer.registerSchema({
      name: type, encoding: "ros2msg", data: new TextEncoder().encode(DEFS[type]) });
    channels[topic] = { id: await writer.registerChannel({
      topic, schemaId, messageEncoding: "cdr", metadata: new Map() }), type };
  }
  let sequence = 0;
  const put = async (topic, sec, message) => {
    const data = writerFor(DEFS[channels[topic].type]).writeMessage(message);
    const t = BigInt(sec) * 1000000000n;
    await writer.addMessage({ channelId: channels[topic].id, sequence: sequence++,
      logTime: t, publishTime: t, data });
  };
  const header = (sec, frame) => ({ stamp: { sec, nanosec: 0 }, frame_id: frame });
  const tf = (sec, parent, child, x) => ({ header: header(sec, parent), child_frame_id: child,
    transform: { translation: { x, y: 0, z: 0 }, rotation: { x: 0, y: 0, z: 0, w: 1 } } });
  await put("/tf_static", 100, { transforms: [tf(100, "odom", "cam_optical", 0.5)] });
  for (let i = 0; i < 3; i++) {
    const sec = 100 + i;
    await put("/tf", sec, { transforms: [tf(sec, "map", "odom", 0.25 * i)] });
    await put("/cam/color/camera_info", sec, { header: header(sec, "cam_optical"), height: H,
      width: W, distortion_model: "plumb_bob", d: [0, 0, 0, 0, 0],
      k: [FX, 0, 3.5, 0, FX, 2.5, 0, 0, 1], r: [1, 0, 0, 0, 1, 0, 0, 0, 1],
      p: [FX, 0, 3.5, 0, 0, FX, 2.5, 0, 0, 0, 1, 0], binning_x: 0, binning_y: 0,
      roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false } });
    await put("/cam/color/image_raw", sec, { header: header(sec, "cam_optical"), height: H,
      width: W, encoding: "rgb8", is_bigendian: 0, step: W * 3,
      data: new Uint8Array(W * H * 3).map((_, k) => (k * 5 + i) % 256) });
    // Depth 1.000 m + 1 mm per pixel index: 1.000 - 1.047 m.
    const depth = new Uint8Array(W * H * 2);
    const view = new DataView(depth.buffer);
    for (let p = 0; p < W * H; p++) view.setUint16(2 * p, 1000 + p, true);
    await put("/cam/depth/image_raw", sec, { header: header(sec, "cam_optical"), height: H,
      width: W, encoding: "16UC1", is_bigendian: 0, step: W * 2, data: depth });
  }
  await writer.end();
  const file = path.join(tmp, "reference.mcap");
  writeFileSync(file, buffer.get());
  let info;
  try {
    info = JSON.parse(execFileSync(semrec, ["info", file, "--json"], { stdio: ["ignore", "pipe", "pipe"] }));
  } catch (e) {
    fail(`semrec info on the @mcap/core bag: ${e.stderr ?? e.message}`);
  }
  const near = (a, b, tol) => Math.abs(a - b) <= tol;
  if (info.frames !== 3) fail(`frames ${info.frames}, not 3`);
  if (info.width !== W || info.height !== H || info.intrinsics.fx !== FX || info.intrinsics.cx !== 3.5) {
    fail(`intrinsics ${JSON.stringify(info.intrinsics)} ${info.width}x${info.height}`);
  }
  if (!near(info.depth_min_m, 1.0, 1e-6) || !near(info.depth_max_m, 1.047, 1e-6)) {
    fail(`depth range ${info.depth_min_m} - ${info.depth_max_m}, not 1.000 - 1.047`);
  }
  if (!near(info.trajectory_length_m, 0.5, 1e-9)) {
    fail(`trajectory ${info.trajectory_length_m} m, not 0.5 (map -> odom moved 0.25 m twice)`);
  }
  if (!info.pose_source.includes("map -> odom -> cam_optical")) fail(`poses: ${info.pose_source}`);
  if (!info.details.some((d) => d.includes("read by the summary's chunk index"))) {
    fail(`the summary's chunk index was not used: ${info.details.join("; ")}`);
  }
  console.log("semrec reads the @mcap/core bag: 3 frames, intrinsics, depth and poses as written");
}

// --- 2. semrec writes, @mcap/core + rosmsg2-serialization read -------------------------------
{
  const seq = path.join(tmp, "syn");
  execFileSync(semrec, ["synth", "--preset", "six-objects", "--frames", "3", "--width", "64",
    "--height", "48", "--out", seq], { stdio: "ignore" });
  const file = path.join(tmp, "semrec.mcap");
  execFileSync(makeBag, [seq, file, "--bare", "--compression", "none"]);
  const reader = new mcap.McapStreamReader({ validateCrcs: true });
  reader.append(readFileSync(file));
  const schemas = new Map(), channels = new Map(), counts = {};
  let record, checked = 0;
  while ((record = reader.nextRecord())) {
    if (record.type === "Schema") schemas.set(record.id, record);
    if (record.type === "Channel") channels.set(record.id, record);
    if (record.type !== "Message") continue;
    const channel = channels.get(record.channelId);
    const schema = schemas.get(channel.schemaId);
    const text = new TextDecoder().decode(schema.data);
    const m = readerFor(text).readMessage(record.data);
    counts[channel.topic] = (counts[channel.topic] ?? 0) + 1;
    if (schema.name === "sensor_msgs/msg/Image") {
      if (m.width !== 64 || m.height !== 48 || m.data.length !== m.step * m.height) {
        fail(`${channel.topic}: image ${m.width}x${m.height} step ${m.step} data ${m.data.length}`);
      }
    } else if (schema.name === "sensor_msgs/msg/CameraInfo") {
      // synth scales the focal length 525 with the width: 525 * 64 / 640.
      if (Math.abs(m.k[0] - 52.5) > 1e-9 || m.width !== 64) fail(`camera info k ${m.k}`);
    } else if (schema.name === "tf2_msgs/msg/TFMessage") {
      for (const t of m.transforms) {
        const q = t.transform.rotation;
        if (Math.abs(Math.hypot(q.x, q.y, q.z, q.w) - 1) > 1e-9) fail(`TF ${t.child_frame_id} rotation`);
      }
    }
    checked++;
  }
  if (!reader.done()) fail("McapStreamReader did not reach the end of semrec's file");
  for (const topic of ["/camera/color/image_raw", "/camera/aligned_depth_to_color/image_raw",
    "/camera/color/camera_info"]) {
    if (counts[topic] !== 3) fail(`${topic}: ${counts[topic]} messages, not 3`);
  }
  console.log(`@mcap/core reads semrec's bag (CRCs checked): ${checked} messages decode with its schemas`);
}
