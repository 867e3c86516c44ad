#!/usr/bin/python3
"""Writes the weights of a SAM ONNX decoder export for semrec's own decoder
kernel (src/semrec/segment/sam_kernel.h), which runs the per-prompt work in
one pass per image token block instead of ONNX Runtime's op-by-op passes.

    export_sam_kernel.py DECODER.onnx PROMPT.onnx OUT.bin [MASKS.onnx]

DECODER.onnx is SAM's export (segment_anything's SamOnnxModel: the weights
are found by the node names the exporter gives, "/transformer/layers.0/
self_attn/q_proj/MatMul", ...); PROMPT.onnx is its prompt part made by
split_sam_decoder.py with a mask preview (the preview's two upscaling steps
at one cell, "/semrec_preview/c_w1", ...); MASKS.onnx, its mask part (the
whole upscaling, "/semrec_upscaling/c_w1", ...), adds the kernel's own mask
part ("upscaling.1.w" [256 x 4 * 64]: columns sub-pixel (ky, kx), then
channel; "upscaling.2.w" [64 x 4 * 32]).

The file: one line of JSON ({"format": "semrec-sam-kernel", "version": 1,
"tensors": {name: {"shape": [...], "offset": bytes}}, "scalars": {...}})
ended by a newline, then the tensors as little-endian float32, each at its
offset from the end of that line. Matrices of linear layers are stored
[in, out] (y = x W + b). Needs Debian's python3-onnx only; exits 2 and writes
nothing when the export does not have SAM's structure.
"""
import json
import os
import sys

import numpy as np
import onnx
from onnx import numpy_helper


def fail(msg):
    print(f"export_sam_kernel: {msg}", file=sys.stderr)
    sys.exit(2)


class Graph:
    def __init__(self, path):
        self.path = path
        model = onnx.load(path)
        self.nodes = {n.name: n for n in model.graph.node}
        self.values = {i.name: numpy_helper.to_array(i)
                       for i in model.graph.initializer}
        for n in model.graph.node:
            if n.op_type == "Constant" and n.attribute:
                self.values[n.output[0]] = numpy_helper.to_array(
                    n.attribute[0].t)
        self.producer = {o: n for n in model.graph.node for o in n.output}

    def node(self, name):
        if name not in self.nodes:
            fail(f"{self.path}: no node {name} (not SAM's ONNX export)")
        return self.nodes[name]

    def value(self, name):
        if name not in self.values:
            fail(f"{self.path}: no constant {name}")
        return self.values[name].astype(np.float32)

    def const_input(self, node_name):
        """The one constant input of a node."""
        node = self.node(node_name)
        found = [i for i in node.input if i in self.values]
        if len(found) != 1:
            fail(f"{self.path}: node {node_name} has {len(found)} constant "
                 "inputs, expected 1")
        return self.value(found[0])


def main(argv):
    if len(argv) not in (4, 5):
        print(__doc__, file=sys.stderr)
        return 2
    dec, prompt = Graph(argv[1]), Graph(argv[2])
    masks = Graph(argv[4]) if len(argv) == 5 else None
    tensors = {}

    def linear(key, prefix):
        w = dec.const_input(prefix + "/MatMul")
        b = dec.const_input(prefix + "/Add")
        if w.ndim != 2 or b.shape != (w.shape[1],):
            fail(f"{argv[1]}: {prefix} has weight {w.shape}, bias {b.shape}")
        tensors[key + ".w"], tensors[key + ".b"] = w, b

    def gemm(key, prefix):
        node = dec.node(prefix + "/Gemm")
        trans_b = [a.i for a in node.attribute if a.name == "transB"]
        w, b = dec.value(node.input[1]), dec.value(node.input[2])
        tensors[key + ".w"] = w.T.copy() if trans_b == [1] else w
        tensors[key + ".b"] = b

    def norm(key, prefix):
        node = dec.node(prefix + "/LayerNormalization")
        tensors[key + ".g"] = dec.value(node.input[1])
        tensors[key + ".b"] = dec.value(node.input[2])

    def attention(key, prefix):
        for p in ("q_proj", "k_proj", "v_proj", "out_proj"):
            linear(f"{key}.{p[0]}", f"{prefix}/{p}")

    for layer in (0, 1):
        t = f"/transformer/layers.{layer}"
        k = f"layers.{layer}"
        attention(k + ".self_attn", t + "/self_attn")
        attention(k + ".t2i", t + "/cross_attn_token_to_image")
        attention(k + ".i2t", t + "/cross_attn_image_to_token")
        linear(k + ".mlp1", t + "/mlp/lin1")
        linear(k + ".mlp2", t + "/mlp/lin2")
        for i in (1, 2, 3, 4):
            norm(f"{k}.norm{i}", f"{t}/norm{i}")
    attention("final", "/transformer/final_attn_token_to_image")
    norm("final_norm", "/transformer/norm_final_attn")
    for i in range(4):
        for j in range(3):
            gemm(f"hyper{i}.{j}", f"/output_hypernetworks_mlps.{i}/layers.{j}")
    for j in range(3):
        gemm(f"iou.{j}", f"/iou_prediction_head/layers.{j}")

    tensors["pe_gaussian"] = dec.value(
        "model.prompt_encoder.pe_layer.positional_encoding_gaussian_matrix")
    tensors["not_a_point"] = dec.value(
        "model.prompt_encoder.not_a_point_embed.weight").reshape(-1)
    tensors["point_embeddings"] = np.stack([
        dec.value(f"model.prompt_encoder.point_embeddings.{i}.weight")
        .reshape(-1) for i in range(4)])
    # The output tokens (IoU token, then the mask tokens) are expanded and
    # put before the prompt's tokens; the dense embedding without a mask is
    # no_mask_embed (the Mul by 1 - has_mask_input).
    concat = dec.producer.get("/Concat_2_output_0")
    expand = dec.producer.get(concat.input[0]) if concat is not None else None
    if expand is None or expand.op_type != "Expand":
        fail(f"{argv[1]}: the output tokens are not where SAM's export puts "
             "them")
    tensors["output_tokens"] = dec.value(expand.input[0]).reshape(-1, 256)
    tensors["no_mask"] = dec.const_input("/Mul_9").reshape(-1)
    reweight = dec.value("/Constant_76_output_0").reshape(-1)
    if reweight.shape != (4,) or np.any(reweight[1:] != 0):
        fail(f"{argv[1]}: the mask choice is not SAM's export's")

    for name in ("c_w1", "c_b1", "c_w2", "c_b2"):
        tensors["preview." + name[2:]] = prompt.value("/semrec_preview/" + name)
    tensors["preview.g"] = prompt.value("/semrec_upscaling/c_gamma")
    tensors["preview.beta"] = prompt.value("/semrec_upscaling/c_beta")
    preview_ln = prompt.node("/semrec_preview/ln")
    preview_eps = [a.f for a in preview_ln.attribute if a.name == "epsilon"]
    norm_eps = [a.f for a in
                dec.node("/transformer/layers.0/norm1/LayerNormalization")
                .attribute if a.name == "epsilon"]

    if masks is not None:
        up = "/semrec_upscaling/"
        for i in (1, 2):
            tensors[f"upscaling.{i}.w"] = masks.value(f"{up}c_w{i}")
            tensors[f"upscaling.{i}.b"] = masks.value(f"{up}c_b{i}")
        # One layer norm for the preview and the mask part: the same one.
        ln = masks.node(up + "ln")
        same = (np.array_equal(masks.value(ln.input[1]), tensors["preview.g"])
                and np.array_equal(masks.value(ln.input[2]),
                                   tensors["preview.beta"])
                and [a.f for a in ln.attribute if a.name == "epsilon"]
                == preview_eps)
        if not same:
            fail(f"{argv[4]}: its layer norm is not the prompt part's preview's")
        # The preview is sub-pixel (1, 1) of the first step, (0, 0) of the
        # second: the same weights.
        if not (np.array_equal(tensors["upscaling.1.w"][:, 192:],
                               tensors["preview.w1"])
                and np.array_equal(tensors["upscaling.2.w"][:, :32],
                                   tensors["preview.w2"])):
            fail(f"{argv[4]}: not the mask part of {argv[2]}")

    shapes = {
        "output_tokens": (5, 256), "pe_gaussian": (2, 128),
        "preview.w1": (256, 64), "preview.w2": (64, 32),
        "upscaling.1.w": (256, 256), "upscaling.1.b": (256,),
        "upscaling.2.w": (64, 128), "upscaling.2.b": (128,),
        "layers.0.mlp1.w": (256, None),
    }
    for name, shape in shapes.items():
        if name not in tensors and name.startswith("upscaling."):
            continue
        got = tensors[name].shape
        if len(got) != len(shape) or any(
                s is not None and s != g for s, g in zip(shape, got)):
            fail(f"{name} is {got}, expected {shape}")

    header = {
        "format": "semrec-sam-kernel", "version": 1, "tensors": {},
        "scalars": {
            "heads": 8,
            "norm_eps": norm_eps[0] if norm_eps else 1e-5,
            "preview_eps": preview_eps[0] if preview_eps else 1e-6,
            "points_offset": float(dec.value("/Constant_75_output_0")),
            "first_mask_reweight": float(reweight[0]),
            "input_size": float(dec.value("/Constant_2_output_0")),
        },
    }
    blobs, offset = [], 0
    for name in sorted(tensors):
        a = np.ascontiguousarray(tensors[name], dtype="<f4")
        header["tensors"][name] = {"shape": list(a.shape), "offset": offset}
        blobs.append(a.tobytes())
        offset += len(blobs[-1])
    tmp = argv[3] + ".tmp"
    with open(tmp, "wb") as f:
        f.write(json.dumps(header, separators=(",", ":")).encode() + b"\n")
        for b in blobs:
            f.write(b)
    os.replace(tmp, argv[3])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
