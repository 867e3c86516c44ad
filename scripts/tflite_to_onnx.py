#!/usr/bin/python3
"""Converts a (quantized) TFLite segmentation model to an ONNX model that runs in float.

    tflite_to_onnx.py MODEL.tflite OUT.onnx --schema schema.fbs
                      [--output labels|logits|both] [--fp16] [--no-clamp]

Every quantized tensor is dequantized (weights and biases to float initializers; activations
computed in float) and every activation is clamped to the range its quantized tensor can
represent, scale * (q_min - zero_point) .. scale * (q_max - zero_point), intersected with the
fused activation. The clamps are not optional in practice: quantized graphs often express a
ReLU6 only as that range (`--no-clamp` exists to show what breaks without them).

Layout: TFLite is NHWC; the ONNX graph is NCHW throughout (the graph input `image` is
[1, 3, H, W], float, already normalised as the TFLite input's quantization implies: the values
the quantized network sees are scale * (pixel - zero_point); the scale and zero point are
recorded in the model's metadata as `input_scale` / `input_zero_point`).

Outputs: `labels` (int32 [1, H, W]: the TFLite model's ARG_MAX) and/or `logits` (float
[1, K, H, W]: the tensor that feeds the ARG_MAX); `coarse-logits`: when that tensor is a
RESIZE_BILINEAR of a coarser one, the coarse one as `logits` (a 512x512x32 map is 16x the
128x128 one: semrec upsamples to the image itself, once; the grid alignment to register,
`asymmetric` or `half_pixel`, is printed and stored in the metadata as `logits_grid`). `--fp16` stores the weights as float16 (half
the file; a Cast per weight is folded by ONNX Runtime when the session starts).

Operators: CONV_2D, DEPTHWISE_CONV_2D, ADD, AVERAGE_POOL_2D, SPLIT, CONCATENATION, QUANTIZE,
DEQUANTIZE, RESIZE_BILINEAR, ARG_MAX. Anything else stops the conversion with an error naming
the operator and the file. Exit status: 0 done, 1 conversion error, 2 usage error.
"""

import argparse
import hashlib
import os
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tflite_schema  # noqa: E402

CONVERTER_VERSION = "1"
OPSET = 13
# NHWC axis -> NCHW axis for rank-4 tensors.
NHWC_TO_NCHW_AXIS = {0: 0, 1: 2, 2: 3, 3: 1}


class ConversionError(Exception):
    pass


class Converter:
    def __init__(self, tflite, model, path, clamp=True, fp16=False):
        self.tfl = tflite
        self.model = model
        self.path = path
        self.clamp = clamp
        self.fp16 = fp16
        self.names = tflite_schema.builtin_names(tflite)
        if len(model.subgraphs) != 1:
            raise ConversionError(f"{path}: {len(model.subgraphs)} subgraphs; only single-graph "
                                  "models are supported")
        self.graph = model.subgraphs[0]
        self.nodes = []
        self.initializers = []
        self.values = {}  # tensor index -> ONNX value name (float, NCHW when rank 4)
        self.ranges = {}  # ONNX value name -> (lo, hi) known bounds of its values
        self.counter = 0
        self.resized_from = {}  # tensor index -> (ONNX value, NHWC shape, mode) before a resize
        self.coarse = None

    # ---- tensors --------------------------------------------------------------------------
    def tensor(self, i):
        return self.graph.tensors[i]

    def tname(self, i):
        t = self.tensor(i)
        return t.name.decode() if isinstance(t.name, bytes) else str(t.name)

    def shape(self, i):
        s = self.tensor(i).shape
        return [] if s is None else [int(d) for d in s]

    def quant(self, i):
        q = self.tensor(i).quantization
        if q is None or q.scale is None or len(q.scale) == 0:
            return None
        zp = q.zeroPoint if q.zeroPoint is not None and len(q.zeroPoint) else [0] * len(q.scale)
        return np.asarray(q.scale, np.float64), np.asarray(zp, np.int64), q.quantizedDimension

    def type_name(self, i):
        from tflite.TensorType import TensorType
        names = {v: k for k, v in vars(TensorType).items() if not k.startswith("_")}
        return names.get(self.tensor(i).type, str(self.tensor(i).type))

    def buffer(self, i):
        b = self.model.buffers[self.tensor(i).buffer]
        if b is None or b.data is None or len(b.data) == 0:
            return None
        return bytes(bytearray(b.data))

    def const_array(self, i):
        """The constant tensor i dequantized to float64, in its TFLite layout."""
        data = self.buffer(i)
        if data is None:
            raise ConversionError(f"{self.path}: tensor '{self.tname(i)}' should be a constant "
                                  "but has no data")
        dtypes = {"UINT8": np.uint8, "INT8": np.int8, "INT16": np.int16, "INT32": np.int32,
                  "INT64": np.int64, "FLOAT32": np.float32, "FLOAT16": np.float16}
        tn = self.type_name(i)
        if tn not in dtypes:
            raise ConversionError(f"{self.path}: tensor '{self.tname(i)}' has type {tn}, "
                                  "which this converter does not read")
        arr = np.frombuffer(data, dtype=dtypes[tn]).reshape(self.shape(i) or [])
        q = self.quant(i)
        if q is None or tn.startswith("FLOAT"):
            return arr.astype(np.float64)
        scale, zp, dim = q
        if len(scale) > 1:  # per-channel
            bshape = [1] * arr.ndim
            bshape[dim] = len(scale)
            scale = scale.reshape(bshape)
            zp = zp.reshape(bshape)
        return (arr.astype(np.float64) - zp) * scale

    def int_const(self, i):
        data = self.buffer(i)
        if data is None:
            raise ConversionError(f"{self.path}: tensor '{self.tname(i)}' must be a constant")
        dt = {"INT32": np.int32, "INT64": np.int64}.get(self.type_name(i))
        if dt is None:
            raise ConversionError(f"{self.path}: tensor '{self.tname(i)}' must be an integer "
                                  "constant")
        return np.frombuffer(data, dtype=dt).reshape(self.shape(i) or [])

    def representable_range(self, i):
        """Float range of tensor i's quantized type, or (-inf, inf) for a float tensor."""
        q = self.quant(i)
        bounds = {"UINT8": (0, 255), "INT8": (-128, 127), "INT16": (-32768, 32767)}
        tn = self.type_name(i)
        if q is None or tn not in bounds or len(q[0]) != 1:
            return (-np.inf, np.inf)
        scale, zp = float(q[0][0]), int(q[1][0])
        return (scale * (bounds[tn][0] - zp), scale * (bounds[tn][1] - zp))

    # ---- graph building -------------------------------------------------------------------
    def fresh(self, hint):
        self.counter += 1
        return f"{hint}_{self.counter}"

    def add_initializer(self, array, hint, weight=False):
        name = self.fresh(hint)
        if weight and self.fp16:
            half = name + "_fp16"
            self.initializers.append(numpy_helper.from_array(array.astype(np.float16), half))
            self.nodes.append(helper.make_node("Cast", [half], [name], to=TensorProto.FLOAT))
        else:
            self.initializers.append(numpy_helper.from_array(array, name))
        return name

    def value(self, i, rank4_expected=None):
        """ONNX name of tensor i's float value; constants become initializers (NCHW if rank 4)."""
        if i in self.values:
            return self.values[i]
        arr = self.const_array(i).astype(np.float32)
        if arr.ndim == 4:
            arr = arr.transpose(0, 3, 1, 2)
        elif rank4_expected and 0 < arr.ndim < 4:
            # Broadcast against an NCHW activation: pad to rank 4 in NHWC, then transpose.
            arr = arr.reshape([1] * (4 - arr.ndim) + list(arr.shape)).transpose(0, 3, 1, 2)
        name = self.add_initializer(arr, "const")
        self.values[i] = name
        self.ranges[name] = (float(arr.min()), float(arr.max())) if arr.size else (0.0, 0.0)
        return name

    def activation_range(self, fused, op_name):
        acts = {0: (-np.inf, np.inf), 1: (0.0, np.inf), 2: (-1.0, 1.0), 3: (0.0, 6.0)}
        if fused not in acts:
            raise ConversionError(f"{self.path}: operator {op_name} has fused activation "
                                  f"{fused} (only NONE, RELU, RELU_N1_TO_1, RELU6 are supported)")
        return acts[fused]

    def finish(self, raw, out_index, fused=0, op_name="", known=None):
        """Applies the fused activation and the output's quantized range to `raw`."""
        lo, hi = self.activation_range(fused, op_name)
        if self.clamp:
            qlo, qhi = self.representable_range(out_index)
            lo, hi = max(lo, qlo), min(hi, qhi)
        name = raw
        if known is not None and known[0] >= lo and known[1] <= hi:
            pass  # already within range (e.g. a split or resize of a clamped tensor)
        elif np.isfinite(lo) or np.isfinite(hi):
            args = [raw, self.add_initializer(np.array(lo if np.isfinite(lo) else -3.4e38,
                                                       np.float32), "lo"),
                    self.add_initializer(np.array(hi if np.isfinite(hi) else 3.4e38,
                                                  np.float32), "hi")]
            name = self.fresh("clip")
            self.nodes.append(helper.make_node("Clip", args, [name]))
        self.values[out_index] = name
        inner = known if known is not None else (-np.inf, np.inf)
        self.ranges[name] = (max(lo, inner[0]), min(hi, inner[1]))
        return name

    def axis(self, axis, rank):
        if axis < 0:
            axis += rank
        return NHWC_TO_NCHW_AXIS[axis] if rank == 4 else axis

    @staticmethod
    def same_pads(in_hw, k_hw, stride_hw, dil_hw):
        pads_begin, pads_end = [], []
        for n, k, s, d in zip(in_hw, k_hw, stride_hw, dil_hw):
            out = -(-n // s)
            total = max((out - 1) * s + (k - 1) * d + 1 - n, 0)
            pads_begin.append(total // 2)
            pads_end.append(total - total // 2)
        return pads_begin + pads_end

    def options(self, op, cls_name):
        opts = op.builtinOptions
        if opts is None:
            raise ConversionError(f"{self.path}: operator {cls_name} without options")
        return opts

    # ---- operators ------------------------------------------------------------------------
    def conv(self, op, depthwise):
        name = "DEPTHWISE_CONV_2D" if depthwise else "CONV_2D"
        o = self.options(op, name)
        x, w, b = op.inputs[0], op.inputs[1], (op.inputs[2] if len(op.inputs) > 2 else -1)
        weights = self.const_array(w)
        in_shape = self.shape(x)
        if depthwise:
            # [1, kh, kw, C * multiplier] -> [C * multiplier, 1, kh, kw], one group per channel.
            kh, kw = weights.shape[1], weights.shape[2]
            onnx_w = weights.transpose(3, 0, 1, 2)
            group = in_shape[3]
        else:
            kh, kw = weights.shape[1], weights.shape[2]
            onnx_w = weights.transpose(0, 3, 1, 2)
            group = 1
        stride = [o.strideH, o.strideW]
        dil = [o.dilationHFactor or 1, o.dilationWFactor or 1]
        if o.padding == 0:  # SAME
            pads = self.same_pads(in_shape[1:3], [kh, kw], stride, dil)
        else:
            pads = [0, 0, 0, 0]
        inputs = [self.value(x),
                  self.add_initializer(onnx_w.astype(np.float32), "w", weight=True)]
        if b >= 0:
            inputs.append(self.add_initializer(self.const_array(b).astype(np.float32), "b",
                                               weight=True))
        raw = self.fresh("conv")
        self.nodes.append(helper.make_node("Conv", inputs, [raw], kernel_shape=[kh, kw],
                                           strides=stride, dilations=dil, pads=pads,
                                           group=group))
        self.finish(raw, op.outputs[0], o.fusedActivationFunction, name)

    def add(self, op):
        o = op.builtinOptions
        fused = o.fusedActivationFunction if o is not None else 0
        rank = len(self.shape(op.outputs[0]))
        a = self.value(op.inputs[0], rank4_expected=rank == 4)
        b = self.value(op.inputs[1], rank4_expected=rank == 4)
        raw = self.fresh("add")
        self.nodes.append(helper.make_node("Add", [a, b], [raw]))
        ra, rb = self.ranges.get(a, (-np.inf, np.inf)), self.ranges.get(b, (-np.inf, np.inf))
        self.finish(raw, op.outputs[0], fused, "ADD", known=(ra[0] + rb[0], ra[1] + rb[1]))

    def average_pool(self, op):
        o = self.options(op, "AVERAGE_POOL_2D")
        x = op.inputs[0]
        k = [o.filterHeight, o.filterWidth]
        stride = [o.strideH, o.strideW]
        pads = self.same_pads(self.shape(x)[1:3], k, stride, [1, 1]) if o.padding == 0 \
            else [0, 0, 0, 0]
        raw = self.fresh("avgpool")
        xv = self.value(x)
        # TFLite averages over the valid (unpadded) cells only.
        self.nodes.append(helper.make_node("AveragePool", [xv], [raw], kernel_shape=k,
                                           strides=stride, pads=pads, count_include_pad=0))
        self.finish(raw, op.outputs[0], o.fusedActivationFunction, "AVERAGE_POOL_2D",
                    known=self.ranges.get(xv))

    def split(self, op):
        o = self.options(op, "SPLIT")
        axis_t, x = op.inputs[0], op.inputs[1]
        rank = len(self.shape(x))
        axis = self.axis(int(self.int_const(axis_t).reshape(-1)[0]), rank)
        if self.shape(x)[int(self.int_const(axis_t).reshape(-1)[0])] % o.numSplits:
            raise ConversionError(f"{self.path}: SPLIT into {o.numSplits} unequal parts")
        xv = self.value(x)
        raws = [self.fresh("split") for _ in op.outputs]
        self.nodes.append(helper.make_node("Split", [xv], raws, axis=axis))
        for raw, out in zip(raws, op.outputs):
            self.finish(raw, out, 0, "SPLIT", known=self.ranges.get(xv))

    def concat(self, op):
        o = self.options(op, "CONCATENATION")
        rank = len(self.shape(op.outputs[0]))
        ins = [self.value(i, rank4_expected=rank == 4) for i in op.inputs]
        raw = self.fresh("concat")
        self.nodes.append(helper.make_node("Concat", ins, [raw], axis=self.axis(o.axis, rank)))
        rs = [self.ranges.get(v, (-np.inf, np.inf)) for v in ins]
        self.finish(raw, op.outputs[0], o.fusedActivationFunction, "CONCATENATION",
                    known=(min(r[0] for r in rs), max(r[1] for r in rs)))

    def requantize(self, op, name):
        # In float a (re)quantization is the identity plus the new tensor's range.
        xv = self.value(op.inputs[0])
        self.finish(xv, op.outputs[0], 0, name, known=self.ranges.get(xv))

    def resize_bilinear(self, op):
        o = op.builtinOptions
        x, size_t = op.inputs[0], op.inputs[1]
        h, w = [int(v) for v in self.int_const(size_t).reshape(-1)[:2]]
        c = self.shape(x)[3]
        align = bool(o.alignCorners) if o is not None else False
        half = bool(o.halfPixelCenters) if o is not None else False
        mode = "align_corners" if align else ("half_pixel" if half else "asymmetric")
        sizes = self.add_initializer(np.array([1, c, h, w], np.int64), "sizes")
        raw = self.fresh("resize")
        xv = self.value(x)
        self.nodes.append(helper.make_node("Resize", [xv, "", "", sizes], [raw], mode="linear",
                                           coordinate_transformation_mode=mode))
        self.resized_from[op.outputs[0]] = (xv, self.shape(x), mode)
        self.finish(raw, op.outputs[0], 0, "RESIZE_BILINEAR", known=self.ranges.get(xv))

    def arg_max(self, op):
        x, axis_t = op.inputs[0], op.inputs[1]
        rank = len(self.shape(x))
        axis = self.axis(int(self.int_const(axis_t).reshape(-1)[0]), rank)
        xv = self.value(x)
        self.logits = xv
        self.logits_shape = self.shape(x)
        self.coarse = self.resized_from.get(x)
        raw = self.fresh("argmax")
        self.nodes.append(helper.make_node("ArgMax", [xv], [raw], axis=axis, keepdims=0))
        name = self.fresh("labels")
        self.nodes.append(helper.make_node("Cast", [raw], [name], to=TensorProto.INT32))
        self.values[op.outputs[0]] = name

    # ---- driver ---------------------------------------------------------------------------
    def convert(self, output="labels"):
        g = self.graph
        if len(g.inputs) != 1:
            raise ConversionError(f"{self.path}: {len(g.inputs)} inputs; one image is expected")
        in_idx = int(g.inputs[0])
        in_shape = self.shape(in_idx)
        if len(in_shape) != 4 or in_shape[3] != 3:
            raise ConversionError(f"{self.path}: input shape {in_shape}; expected [1, H, W, 3]")
        self.values[in_idx] = "image"
        self.ranges["image"] = self.representable_range(in_idx)
        self.logits = None
        handlers = {
            "CONV_2D": lambda op: self.conv(op, depthwise=False),
            "DEPTHWISE_CONV_2D": lambda op: self.conv(op, depthwise=True),
            "ADD": self.add,
            "AVERAGE_POOL_2D": self.average_pool,
            "SPLIT": self.split,
            "CONCATENATION": self.concat,
            "QUANTIZE": lambda op: self.requantize(op, "QUANTIZE"),
            "DEQUANTIZE": lambda op: self.requantize(op, "DEQUANTIZE"),
            "RESIZE_BILINEAR": self.resize_bilinear,
            "ARG_MAX": self.arg_max,
        }
        unsupported = sorted({self.names.get(tflite_schema.op_code(self.model, op), "?")
                              for op in g.operators} - set(handlers))
        if unsupported:
            raise ConversionError(f"{self.path}: unsupported TFLite operator(s): "
                                  f"{', '.join(unsupported)} (supported: "
                                  f"{', '.join(sorted(handlers))})")
        for op in g.operators:
            handlers[self.names[tflite_schema.op_code(self.model, op)]](op)

        if len(g.outputs) != 1:
            raise ConversionError(f"{self.path}: {len(g.outputs)} outputs; one is expected")
        out_idx = int(g.outputs[0])
        outputs = []
        h, w = in_shape[1], in_shape[2]
        if output in ("labels", "both"):
            if self.logits is None:
                raise ConversionError(f"{self.path}: the graph does not end in ARG_MAX; "
                                      "use --output logits")
            self.nodes.append(helper.make_node("Identity", [self.values[out_idx]], ["labels"]))
            outputs.append(helper.make_tensor_value_info("labels", TensorProto.INT32,
                                                         [1] + self.shape(out_idx)[1:]))
        if output == "coarse-logits":
            if self.coarse is None:
                raise ConversionError(f"{self.path}: the ARG_MAX input is not a RESIZE_BILINEAR; "
                                      "use --output logits")
            if self.coarse[2] == "align_corners":
                raise ConversionError(f"{self.path}: the final resize aligns corners, which "
                                      "semrec's logits grid cannot express; use --output logits")
            self.logits, self.logits_shape = self.coarse[0], self.coarse[1]
            self.logits_grid = self.coarse[2] if self.coarse[2] == "asymmetric" else "half_pixel"
        if output in ("logits", "both", "coarse-logits"):
            src, shape = self.logits, getattr(self, "logits_shape", None)
            if src is None:
                src, shape = self.values[out_idx], self.shape(out_idx)
            if len(shape) == 4:
                shape = [shape[0], shape[3], shape[1], shape[2]]
            self.nodes.append(helper.make_node("Identity", [src], ["logits"]))
            outputs.append(helper.make_tensor_value_info("logits", TensorProto.FLOAT, shape))
        inputs = [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 3, h, w])]
        # Only what the outputs need (coarse logits leave the final resize and ARG_MAX unused).
        needed = {o.name for o in outputs}
        live = []
        for node in reversed(self.nodes):
            if any(out in needed for out in node.output):
                live.append(node)
                needed.update(i for i in node.input if i)
        live.reverse()
        inits = [t for t in self.initializers if t.name in needed]
        graph = helper.make_graph(live, "tflite", inputs, outputs, inits)
        model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)],
                                  producer_name="semrec tflite_to_onnx.py",
                                  producer_version=CONVERTER_VERSION)
        q = self.quant(in_idx)
        meta = {"source": os.path.basename(self.path), "clamped": str(self.clamp).lower(),
                "logits_grid": getattr(self, "logits_grid", "half_pixel")}
        if q is not None:
            meta["input_scale"] = repr(float(q[0][0]))
            meta["input_zero_point"] = str(int(q[1][0]))
        for k, v in meta.items():
            entry = model.metadata_props.add()
            entry.key, entry.value = k, v
        return model


def meta_value(model, key):
    return next((p.value for p in model.metadata_props if p.key == key), "")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("tflite", help="the .tflite model")
    parser.add_argument("onnx", help="the .onnx file to write (atomically)")
    parser.add_argument("--schema", required=True, help="TFLite's schema.fbs")
    parser.add_argument("--output", choices=["labels", "logits", "coarse-logits", "both"],
                        default="labels",
                        help="labels: the ARG_MAX (int32); logits: the float tensor feeding it; "
                             "coarse-logits: that tensor before its final resize")
    parser.add_argument("--fp16", action="store_true", help="store the weights as float16")
    parser.add_argument("--no-clamp", action="store_true",
                        help="do not clamp activations to their quantized range (wrong for "
                             "most quantized models; for tests)")
    args = parser.parse_args(argv)
    try:
        tfl = tflite_schema.load(args.schema)
        model = tflite_schema.read_model(tfl, args.tflite)
        onnx_model = Converter(tfl, model, args.tflite, clamp=not args.no_clamp,
                               fp16=args.fp16).convert(args.output)
        onnx.checker.check_model(onnx_model)
    except (ConversionError, tflite_schema.SchemaError) as e:
        print(f"tflite_to_onnx: error: {e}", file=sys.stderr)
        return 1
    tmp = args.onnx + ".tmp"
    onnx.save(onnx_model, tmp)
    os.replace(tmp, args.onnx)
    with open(args.tflite, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    print(f"{args.onnx}: {len(onnx_model.graph.node)} nodes, "
          f"{os.path.getsize(args.onnx)} bytes, from {os.path.basename(args.tflite)} "
          f"(sha256 {digest[:12]}...)"
          + (f"; logits grid: {meta_value(onnx_model, 'logits_grid')}"
             if args.output == "coarse-logits" else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
