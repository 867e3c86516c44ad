#!/usr/bin/python3
"""Splits a SAM-style ONNX mask decoder into an image part and a prompt part.

    split_sam_decoder.py DECODER.onnx IMAGE_PART.onnx PROMPT_PART.onnx [MASK_PART.onnx]

Automatic mask generation decodes ~1000 prompts against one image embedding.
Part of the decoder does not depend on the prompt (projections of the image
tokens in the first two-way attention layer, the dense prompt embedding, the
positional encoding of the image grid): about a fifth of its work. The image
part computes those tensors once per image; the prompt part takes them as
inputs and does the rest per prompt. Only the outputs semrec reads
(iou_predictions, low_res_masks) are kept, so the full-size mask upsampling of
the export is dropped too. The prompt part is then reordered for a CPU
(sam_decoder_rewrites.py: cross-attention with the projections folded into the
few tokens' side, the mask upscaling as channel-last matrix products). With
MASK_PART.onnx, the upscaling moves there and the prompt part gives a preview
of the mask instead (split_mask_part), so that prompts whose mask cannot pass
the filters skip it; when the decoder lacks the structure for that, the prompt
part keeps the upscaling and MASK_PART.onnx is removed if present.

SAM exports compute shapes at run time (e.g. the image embedding is tiled to
the prompt batch size), which ties every image tensor to the prompt through
shape arithmetic. The batch size is fixed at 1 here (as semrec decodes), and
shape arithmetic that gives the same values for different point counts is
folded into constants first; what still depends on the prompt stays in the
prompt part. Needs Debian's python3-onnx (1.12+) and numpy only.
"""
import copy
import os
import sys

import numpy as np
import onnx
from onnx import helper, numpy_helper, shape_inference

from sam_decoder_rewrites import (attr, live_nodes, rewrite_attention, rewrite_upscaling,
                                   split_mask_part)

PROMPT_INPUTS = ("point_coords", "point_labels")
KEEP_OUTPUTS = ("iou_predictions", "low_res_masks")
MAX_FOLD_ELEMENTS = 64  # only shape-sized tensors are folded


def evaluate(node, args):
    """numpy evaluation of the ops that shape arithmetic uses; None = unknown."""
    op = node.op_type
    if op == "Constant":
        return [numpy_helper.to_array(attr(node, "value"))]
    if op in ("Identity",):
        return [args[0]]
    if op == "Cast":
        to = helper.tensor_dtype_to_np_dtype(attr(node, "to")) if hasattr(
            helper, "tensor_dtype_to_np_dtype") else onnx.mapping.TENSOR_TYPE_TO_NP_TYPE[attr(node, "to")]
        return [args[0].astype(to)]
    if op == "Gather":
        return [np.take(args[0], args[1], axis=attr(node, "axis", 0))]
    if op == "Unsqueeze":
        axes = args[1] if len(args) > 1 else attr(node, "axes")
        out = args[0]
        for a in sorted(int(a) % (out.ndim + len(axes)) for a in axes):
            out = np.expand_dims(out, a)
        return [out]
    if op == "Squeeze":
        axes = args[1] if len(args) > 1 else attr(node, "axes")
        return [np.squeeze(args[0], axis=None if axes is None else tuple(int(a) for a in axes))]
    if op == "Concat":
        return [np.concatenate(args, axis=attr(node, "axis"))]
    binary = {"Add": np.add, "Sub": np.subtract, "Mul": np.multiply,
              "Equal": np.equal, "Less": np.less, "Greater": np.greater,
              "Max": np.maximum, "Min": np.minimum}
    if op in binary:
        return [binary[op](args[0], args[1]).astype(
            bool if op in ("Equal", "Less", "Greater") else np.result_type(args[0], args[1]))]
    if op == "Div":
        if np.issubdtype(args[0].dtype, np.integer):
            return [(np.trunc(args[0] / args[1])).astype(args[0].dtype)]
        return [args[0] / args[1]]
    if op == "Not":
        return [np.logical_not(args[0])]
    if op == "Floor":
        return [np.floor(args[0])]
    if op == "Where":
        return [np.where(args[0], args[1], args[2])]
    if op == "Slice":
        data, starts, ends = args[0], args[1], args[2]
        axes = args[3] if len(args) > 3 and args[3] is not None else range(len(starts))
        steps = args[4] if len(args) > 4 and args[4] is not None else [1] * len(starts)
        index = [slice(None)] * data.ndim
        for s, e, a, st in zip(starts, ends, axes, steps):
            index[int(a)] = slice(int(s), int(e), int(st))
        return [data[tuple(index)]]
    if op == "ConstantOfShape":
        value = attr(node, "value")
        fill = numpy_helper.to_array(value) if value is not None else np.zeros(1, np.float32)
        return [np.full(tuple(int(d) for d in args[0]), fill.reshape(-1)[0], dtype=fill.dtype)]
    if op == "Range":
        return [np.arange(args[0], args[1], args[2]).astype(args[0].dtype)]
    if op == "Reshape":
        shape = [int(d) for d in args[1]]
        shape = [args[0].shape[i] if d == 0 else d for i, d in enumerate(shape)]
        return [args[0].reshape(shape)]
    if op == "Expand":
        return [args[0] * np.ones(tuple(int(d) for d in args[1]), dtype=args[0].dtype)]
    if op == "Tile":
        return [np.tile(args[0], tuple(int(r) for r in args[1]))]
    if op == "OneHot":
        indices, depth, values = args[0], int(np.asarray(args[1]).reshape(-1)[0]), args[2]
        hot = np.arange(depth) == np.expand_dims(np.where(indices < 0, indices + depth, indices), -1)
        out = np.where(hot, values[1], values[0]).astype(values.dtype)
        return [np.moveaxis(out, -1, attr(node, "axis", -1))]
    if op == "ReduceProd":
        return [np.prod(args[0], keepdims=bool(attr(node, "keepdims", 1)))]
    return None


def read_shapes(model):
    shapes, types = {}, {}
    for vi in list(model.graph.value_info) + list(model.graph.input) + list(model.graph.output):
        t = vi.type.tensor_type
        types[vi.name] = t.elem_type
        if t.HasField("shape") and all(d.HasField("dim_value") for d in t.shape.dim):
            shapes[vi.name] = [d.dim_value for d in t.shape.dim]
    for i in model.graph.initializer:
        shapes[i.name] = list(i.dims)
        types[i.name] = i.data_type
    return shapes, types


def own_shape(node, shapes, known):
    """Output shape where ONNX 1.12 shape inference gives up (arguments known)."""
    op, ins = node.op_type, node.input
    if op == "OneHot" and ins[0] in shapes and ins[1] in known:
        out = list(shapes[ins[0]])
        axis = attr(node, "axis", -1)
        out.insert(axis % (len(out) + 1), int(np.asarray(known[ins[1]]).reshape(-1)[0]))
        return out
    if op == "Expand" and ins[0] in shapes and ins[1] in known:
        return list(np.broadcast_shapes(tuple(shapes[ins[0]]), tuple(int(d) for d in known[ins[1]])))
    if op == "Reshape" and ins[0] in shapes and ins[1] in known:
        size = int(np.prod(shapes[ins[0]]))
        out = [shapes[ins[0]][k] if d == 0 else int(d) for k, d in enumerate(known[ins[1]])]
        if -1 in out:
            rest = int(np.prod([d for d in out if d != -1]))
            out[out.index(-1)] = size // rest
        return out
    return None


def static_shapes(model, known):
    """Static shapes of all tensors that have one (ONNX inference + own rules)."""
    m = copy.deepcopy(model)
    while True:
        m = shape_inference.infer_shapes(m)
        shapes, types = read_shapes(m)
        added = False
        for node in m.graph.node:
            if node.output[0] in shapes:
                continue
            out = own_shape(node, shapes, known)
            if out is None or node.op_type not in ("OneHot", "Expand", "Reshape"):
                continue
            elem = types.get(node.input[2] if node.op_type == "OneHot" else node.input[0], 0)
            if not elem:
                continue
            m.graph.value_info.append(helper.make_tensor_value_info(node.output[0], elem, out))
            added = True
        if not added:
            return shapes, types


def set_prompt_points(model, points):
    for value in model.graph.input:
        if value.name in PROMPT_INPUTS:
            dims = value.type.tensor_type.shape.dim
            dims[0].ClearField("dim_param")
            dims[0].dim_value = 1
            dims[1].ClearField("dim_param")
            if points is None:
                dims[1].dim_param = "num_points"
            else:
                dims[1].dim_value = points


def fold_values(model, points):
    """Values of all shape-sized tensors computable for a fixed point count."""
    m = copy.deepcopy(model)
    set_prompt_points(m, points)
    known = {i.name: numpy_helper.to_array(i) for i in m.graph.initializer}
    big = set(known)  # weights: known but never folded into new constants
    while True:
        shapes, _ = static_shapes(m, known)
        added = False
        for node in m.graph.node:
            if all(o in known for o in node.output):
                continue
            values = None
            if node.op_type == "Shape" and node.input[0] in shapes:
                s = np.array(shapes[node.input[0]], dtype=np.int64)
                values = [s[attr(node, "start", 0):attr(node, "end", len(s))]]
            elif all((not i) or i in known for i in node.input):
                values = evaluate(node, [known[i] if i else None for i in node.input])
            if values is None:
                continue
            for name, value in zip(node.output, values):
                known[name] = np.asarray(value)
                added = True
        if not added:
            break
        # Replace folded nodes by initializers so that shape inference sees
        # static Reshape/Tile/OneHot arguments on the next round.
        small = lambda name: name in known and known[name].size <= MAX_FOLD_ELEMENTS
        folded_nodes = [n for n in m.graph.node if all(small(o) for o in n.output)]
        have = set(i.name for i in m.graph.initializer)
        for n in folded_nodes:
            for name in n.output:
                if name not in have:
                    m.graph.initializer.append(numpy_helper.from_array(known[name], name))
        rest = [n for n in m.graph.node if not all(small(o) for o in n.output)]
        m.graph.ClearField("node")
        m.graph.node.extend(rest)
        m.graph.ClearField("value_info")
    return {k: v for k, v in known.items() if k not in big and v.size <= MAX_FOLD_ELEMENTS}


def with_constants(nodes, chosen, is_constant):
    """The chosen nodes plus the constant-only nodes they need, in order."""
    producer = {o: k for k, n in enumerate(nodes) for o in n.output}
    take = list(chosen)
    stack = [k for k, c in enumerate(chosen) if c]
    while stack:
        for i in nodes[stack.pop()].input:
            k = producer.get(i)
            if k is not None and is_constant[k] and not take[k]:
                take[k] = True
                stack.append(k)
    return [n for n, t in zip(nodes, take) if t]


def split(model, mask_part=True):
    graph = model.graph
    outputs = [o for o in graph.output if o.name in KEEP_OUTPUTS]
    if len(outputs) != len(KEEP_OUTPUTS):
        raise SystemExit("the decoder lacks outputs %s" % (KEEP_OUTPUTS,))
    # Shape values that do not change with the point count become constants.
    a, b = fold_values(model, 2), fold_values(model, 7)
    folded = {k: v for k, v in a.items()
              if k in b and v.shape == b[k].shape and np.array_equal(v, b[k])
              and k not in KEEP_OUTPUTS}
    set_prompt_points(model, None)
    nodes = [n for n in graph.node if not all(o in folded for o in n.output)]
    initializers = {i.name: i for i in graph.initializer}
    for name, value in folded.items():
        initializers[name] = numpy_helper.from_array(value, name)

    # Keep only what the kept outputs need.
    kept = live_nodes(nodes, [o.name for o in outputs])

    prompt_dependent = set(PROMPT_INPUTS)
    for n in kept:
        if any(i in prompt_dependent for i in n.input):
            prompt_dependent.update(n.output)
    constant = set(initializers)
    for n in kept:
        if all((not i) or i in constant for i in n.input):
            constant.update(n.output)  # ONNX Runtime folds these itself
    is_constant = [all(o in constant for o in n.output) for n in kept]
    is_prompt = [any(o in prompt_dependent for o in n.output) for n in kept]
    image_nodes = with_constants(kept, [not c and not p for c, p in zip(is_constant, is_prompt)],
                                 is_constant)
    # A constant output (an export's fixed IoU) is computed by the prompt part.
    out_names = set(o.name for o in outputs)
    wanted = [p or (c and any(o in out_names for o in n.output))
              for n, c, p in zip(kept, is_constant, is_prompt)]
    for n, c, p in zip(kept, is_constant, is_prompt):
        if not c and not p and any(o in out_names for o in n.output):
            raise SystemExit("output %s does not depend on the prompt" % n.output[0])
    prompt_nodes = with_constants(kept, wanted, is_constant)

    image_tensors = set(o for n, c in zip(kept, is_constant) if not c for o in n.output)
    image_tensors -= prompt_dependent
    frontier = []
    for n in prompt_nodes:
        for i in n.input:
            if i in image_tensors and i not in frontier:
                frontier.append(i)
    # Inputs the prompt part reads directly (the prompt, or an image-side input
    # it uses unchanged) stay its inputs.
    prompt_side_inputs = [i for i in graph.input
                          if any(i.name in n.input for n in prompt_nodes)]

    # Types and shapes of the frontier tensors (batch fixed at 1).
    probe = copy.deepcopy(model)
    set_prompt_points(probe, 2)
    probe.graph.ClearField("node")
    probe.graph.node.extend(kept)
    probe.graph.ClearField("initializer")
    probe.graph.initializer.extend(initializers.values())
    probe.graph.ClearField("value_info")
    shapes, types = static_shapes(probe, folded)
    frontier_values = []
    for f in frontier:
        if f not in shapes:
            raise SystemExit("cannot infer the shape of %s" % f)
        if types[f] != onnx.TensorProto.FLOAT:
            raise SystemExit("%s is not float32; the split would need other input types" % f)
        frontier_values.append(helper.make_tensor_value_info(f, types[f], shapes[f]))

    def used_initializers(node_list):
        used = set(i for n in node_list for i in n.input)
        return [initializers[k] for k in initializers if k in used]

    def make(name, node_list, inputs, outs):
        used = set(i for n in node_list for i in n.input)
        g = helper.make_graph(node_list, name, [i for i in inputs if i.name in used],
                              outs, used_initializers(node_list))
        m = helper.make_model(g, opset_imports=model.opset_import,
                              producer_name="semrec split_sam_decoder.py")
        m.ir_version = model.ir_version
        onnx.checker.check_model(m)
        return m

    image_inputs = [i for i in graph.input if i.name not in PROMPT_INPUTS]
    image_part = make("sam_decoder_image_part", image_nodes, image_inputs, frontier_values)
    prompt_part = make("sam_decoder_prompt_part", prompt_nodes,
                       prompt_side_inputs + frontier_values, outputs)
    upscaling_rewritten = rewrite_upscaling(prompt_part)
    attention_blocks_rewritten = rewrite_attention(prompt_part)
    mask_part = split_mask_part(prompt_part) if upscaling_rewritten and mask_part else None
    if upscaling_rewritten or attention_blocks_rewritten:
        onnx.checker.check_model(prompt_part)
    if mask_part is not None:
        onnx.checker.check_model(mask_part)
    return image_part, prompt_part, mask_part, frontier


def main():
    if len(sys.argv) not in (4, 5):
        raise SystemExit(__doc__)
    model = onnx.load(sys.argv[1])
    # Without a place for a mask part the prompt part keeps the upscaling.
    image_part, prompt_part, mask_part, frontier = split(model, mask_part=len(sys.argv) == 5)
    onnx.save(image_part, sys.argv[2])
    onnx.save(prompt_part, sys.argv[3])
    if len(sys.argv) == 5:
        if mask_part is None:
            # The prompt part computes the masks itself; an old mask part
            # must not be paired with it.
            if os.path.exists(sys.argv[4]):
                os.remove(sys.argv[4])
        else:
            onnx.save(mask_part, sys.argv[4])
    print("split %s: %d image-part nodes, %d prompt-part nodes, %s, %d tensors passed" %
          (sys.argv[1], len(image_part.graph.node), len(prompt_part.graph.node),
           "%d mask-part nodes" % len(mask_part.graph.node) if mask_part else "no mask part",
           len(frontier)))


if __name__ == "__main__":
    main()
