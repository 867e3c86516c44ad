"""Rewrites of a SAM decoder's prompt part that keep its arithmetic (up to
float rounding) but do far less work per prompt on a CPU; used by
split_sam_decoder.py. Each returns without changing the model when the graph
does not have the exact structure of the SAM export it was written for.
"""
import copy

import numpy as np
import onnx
from onnx import helper, numpy_helper


def attr(node, name, default=None):
    for a in node.attribute:
        if a.name == name:
            return helper.get_attribute_value(a)
    return default


def live_nodes(nodes, outputs):
    """The nodes that the tensors named in `outputs` need, in their order."""
    needed = set(outputs)
    live = []
    for n in reversed(list(nodes)):
        if any(o in needed for o in n.output):
            live.append(n)
            needed.update(i for i in n.input if i)
    return live[::-1]


def replace_node(graph, old, new_nodes):
    """Puts `new_nodes` where `old` was (its inputs are defined by then)."""
    at = [k for k, n in enumerate(graph.node) if n is old][0]
    order = list(graph.node[:at]) + new_nodes + list(graph.node[at + 1:])
    graph.ClearField("node")
    graph.node.extend(order)


def finish(graph, new_initializers):
    """Adds the rewrite's constants, then drops the nodes and initializers
    that no output needs any more (the replaced path)."""
    for name, value in new_initializers.items():
        graph.initializer.append(numpy_helper.from_array(value, name))
    live = live_nodes(graph.node, [o.name for o in graph.output])
    graph.ClearField("node")
    graph.node.extend(live)
    used = set(i for n in graph.node for i in n.input)
    keep = [i for i in graph.initializer if i.name in used]
    graph.ClearField("initializer")
    graph.initializer.extend(keep)


class Nodes:
    """New nodes named under one prefix, each output named like its node (or
    `output`), in the order built; gelu() spells SAM's exact GELU with the
    constants gelu_constants() names."""

    def __init__(self, prefix):
        self.prefix, self.list = prefix, []

    def add(self, op, inputs, name, output=None, **attrs):
        out = output or self.prefix + name
        self.list.append(helper.make_node(op, inputs, [out], name=self.prefix + name, **attrs))
        return out

    def gelu(self, x, name):
        """x * 0.5 * (1 + erf(x / sqrt 2))."""
        p, add = self.prefix, self.add
        e = add("Erf", [add("Div", [x, p + "c_sqrt2"], name + "_div")], name + "_erf")
        y = add("Mul", [x, add("Add", [e, p + "c_one"], name + "_add")], name + "_mul")
        return add("Mul", [y, p + "c_half"], name)


def gelu_constants(prefix):
    return {prefix + "c_sqrt2": np.array(np.sqrt(2.0), np.float32),
            prefix + "c_one": np.array(1.0, np.float32),
            prefix + "c_half": np.array(0.5, np.float32)}


def rewrite_upscaling(model):
    """SAM's mask upscaling as GEMMs on the channel-last token layout.

    The export runs two 2x2/stride-2 ConvTransposes with a LayerNorm2d and
    GELUs between them on NCHW tensors, then multiplies the 32-channel result
    by the hypernetwork outputs. A 2x2/stride-2 ConvTranspose writes each input
    pixel's 2x2 output block from that pixel alone: a matrix product per pixel.
    Kept channel-last, each step is one GEMM, the LayerNorm2d becomes a fused
    LayerNormalization over the last axis, and only the final [masks x 65536]
    logits are permuted into raster order (instead of the 8 MB feature maps).
    Same arithmetic up to float rounding. Returns False (model unchanged) when
    the decoder does not have this structure.
    """
    g = model.graph
    if max((o.version for o in model.opset_import if o.domain in ("", "ai.onnx")),
           default=0) < 17:
        return False  # LayerNormalization needs opset 17
    inits = {i.name: i for i in g.initializer}
    consumers = {}
    for n in g.node:
        for i in n.input:
            consumers.setdefault(i, []).append(n)
    producer = {o: n for n in g.node for o in n.output}

    def only_consumer(name, op):
        users = consumers.get(name, [])
        return users[0] if len(users) == 1 and users[0].op_type == op else None

    def const(name):
        if name in inits:
            return numpy_helper.to_array(inits[name])
        return None

    convs = [n for n in g.node if n.op_type == "ConvTranspose"]
    if len(convs) != 2:
        return False
    c1, c2 = convs
    for c in convs:
        if (attr(c, "kernel_shape") != [2, 2] or attr(c, "strides") != [2, 2]
                or any(attr(c, "pads", [0, 0, 0, 0])) or attr(c, "group", 1) != 1
                or len(c.input) < 3 or const(c.input[1]) is None or const(c.input[2]) is None):
            return False
    # Input: Reshape(Transpose(tokens [1, HW, C], perm 0 2 1)) -> [1, C, H, W].
    reshape_in = producer.get(c1.input[0])
    transpose_in = producer.get(reshape_in.input[0]) if reshape_in is not None else None
    if (reshape_in is None or reshape_in.op_type != "Reshape" or transpose_in is None
            or transpose_in.op_type != "Transpose" or attr(transpose_in, "perm") != [0, 2, 1]):
        return False
    nchw = const(reshape_in.input[1])
    if nchw is None or len(nchw) != 4:
        return False
    _, channels, height, width = (int(d) for d in nchw)
    tokens = transpose_in.input[0]

    # LayerNorm2d: ReduceMean, Sub, Pow 2, ReduceMean, Add eps, Sqrt, Div, Mul w, Add b.
    x = c1.output[0]
    means = [n for n in consumers.get(x, []) if n.op_type == "ReduceMean"]
    mean = means[0] if len(means) == 1 else None
    chain = {}
    try:
        subs = [n for n in consumers[x] if n.op_type == "Sub"]
        chain["sub"] = subs[0]
        chain["pow"] = only_consumer(chain["sub"].output[0], "Pow") or [
            n for n in consumers[chain["sub"].output[0]] if n.op_type == "Pow"][0]
        chain["mean2"] = only_consumer(chain["pow"].output[0], "ReduceMean")
        chain["eps"] = only_consumer(chain["mean2"].output[0], "Add")
        chain["sqrt"] = only_consumer(chain["eps"].output[0], "Sqrt")
        chain["div"] = only_consumer(chain["sqrt"].output[0], "Div")
        chain["mul"] = only_consumer(chain["div"].output[0], "Mul")
        chain["add"] = only_consumer(chain["mul"].output[0], "Add")
    except (KeyError, IndexError):
        return False
    if mean is None or any(v is None for v in chain.values()):
        return False
    if attr(mean, "axes") != [1] or attr(chain["mean2"], "axes") != [1]:
        return False
    eps = [const(i) for i in chain["eps"].input if const(i) is not None]
    gamma = [const(i) for i in chain["mul"].input if const(i) is not None]
    beta = [const(i) for i in chain["add"].input if const(i) is not None]
    if len(eps) != 1 or len(gamma) != 1 or len(beta) != 1:
        return False

    def gelu_after(name):
        """The exact GELU x * 0.5 * (1 + erf(x / sqrt 2)) reading `name`: its output."""
        div = [n for n in consumers.get(name, []) if n.op_type == "Div"]
        if len(div) != 1:
            return None
        erf = only_consumer(div[0].output[0], "Erf")
        add = erf and only_consumer(erf.output[0], "Add")
        mul = add and only_consumer(add.output[0], "Mul")
        half = mul and only_consumer(mul.output[0], "Mul")
        if half is None or name not in mul.input:
            return None
        return half.output[0]

    gelu1 = gelu_after(chain["add"].output[0])
    if gelu1 is None or only_consumer(gelu1, "ConvTranspose") is not c2:
        return False
    gelu2 = gelu_after(c2.output[0])
    flat = gelu2 and only_consumer(gelu2, "Reshape")
    matmul = flat and only_consumer(flat.output[0], "MatMul")
    if matmul is None or matmul.input[1] != flat.output[0]:
        return False
    hyper = matmul.input[0]  # [1, masks, 32]

    w1, b1 = const(c1.input[1]), const(c1.input[2])  # [C, C1, 2, 2], [C1]
    w2, b2 = const(c2.input[1]), const(c2.input[2])  # [C1, C2, 2, 2], [C2]
    c_in, c_mid = w1.shape[:2]
    c_out = w2.shape[1]
    if c_in != channels or w2.shape[0] != c_mid:
        return False
    # Columns ordered (ky, kx, c): each pixel's 2x2 block, channels last.
    w1g = np.ascontiguousarray(w1.transpose(0, 2, 3, 1).reshape(c_in, 4 * c_mid))
    w2g = np.ascontiguousarray(w2.transpose(0, 2, 3, 1).reshape(c_mid, 4 * c_out))
    prefix = "/semrec_upscaling/"
    new_inits = {
        prefix + "c_w1": w1g.astype(np.float32), prefix + "c_b1": np.tile(b1, 4).astype(np.float32),
        prefix + "c_w2": w2g.astype(np.float32), prefix + "c_b2": np.tile(b2, 4).astype(np.float32),
        prefix + "c_gamma": gamma[0].reshape(-1).astype(np.float32),
        prefix + "c_beta": beta[0].reshape(-1).astype(np.float32),
        prefix + "c_shape1": np.array([1, height * width * 4, c_mid], np.int64),
        prefix + "c_shape2": np.array([1, height * width * 16, c_out], np.int64),
        prefix + "c_blocks": np.array([height, width, 2, 2, 2, 2, -1], np.int64),
        prefix + "c_raster": np.array([1, -1, height * width * 16], np.int64),
        **gelu_constants(prefix),
    }
    built = Nodes(prefix)
    node, gelu = built.add, built.gelu

    a1 = node("Add", [node("MatMul", [tokens, prefix + "c_w1"], "mm1"), prefix + "c_b1"], "up1")
    ln = node("LayerNormalization", [node("Reshape", [a1, prefix + "c_shape1"], "up1_px"),
                                     prefix + "c_gamma", prefix + "c_beta"],
              "ln", axis=-1, epsilon=float(eps[0]))
    a2 = node("Add", [node("MatMul", [gelu(ln, "gelu1"), prefix + "c_w2"], "mm2"), prefix + "c_b2"],
              "up2")
    features = node("Reshape", [gelu(a2, "gelu2"), prefix + "c_shape2"], "features")
    logits = node("MatMul", [features, node("Transpose", [hyper], "hyper_t", perm=[0, 2, 1])],
                  "logits")  # [1, 16 HW, masks], rows (y, x, ky, kx, ky2, kx2)
    blocks = node("Reshape", [logits, prefix + "c_blocks"], "blocks")
    raster = node("Transpose", [blocks], "raster_t", perm=[6, 0, 2, 4, 1, 3, 5])
    node("Reshape", [raster, prefix + "c_raster"], "raster", matmul.output[0])

    # The new Reshape now defines the MatMul's output; the old path goes dead.
    replace_node(g, matmul, built.list)
    finish(g, new_inits)
    return True


def rewrite_attention(model):
    """SAM's cross-attention blocks reordered so that the 4096 image tokens go
    through one 256-wide product per side instead of a projection.

    Token-to-image attention (few queries, 4096 keys): the keys' projection
    is folded into the queries (scores = (q W_k^T) X^T; the key bias adds a
    constant per query, which softmax ignores) and the values' projection is
    applied after averaging (A (X W_v) = (A X) W_v). Image-to-token attention
    (4096 queries, few keys): the query projection is folded into the keys and
    the output projection into the values (out = A (V W_o)). Each replaces a
    [4096 x 256] x [256 x 128] product by one with 8 heads x few tokens
    columns. Blocks whose image-side projections run in the image part are
    left to it. Returns the number of blocks rewritten.
    """
    g = model.graph
    inits = {i.name: i for i in g.initializer}
    by_name = {n.name: n for n in g.node}

    def const(name):
        return numpy_helper.to_array(inits[name]) if name in inits else None

    def linear(prefix):
        """(input, W [in, out], b [out]) of the Linear `prefix`, or None."""
        mm, add = by_name.get(prefix + "/MatMul"), by_name.get(prefix + "/Add")
        if mm is None or add is None or mm.output[0] not in add.input:
            return None
        w = const(mm.input[1])
        b = [const(i) for i in add.input if const(i) is not None]
        if w is None or w.ndim != 2 or len(b) != 1:
            return None
        return mm.input[0], w.astype(np.float32), b[0].astype(np.float32)

    prefixes = sorted(set(n.name[:-len("out_proj/MatMul")] for n in g.node
                          if n.name.endswith("_to_image/out_proj/MatMul")
                          or n.name.endswith("_to_token/out_proj/MatMul")))
    new_inits, count = {}, 0
    for prefix in prefixes:
        out = by_name.get(prefix + "out_proj/Add")
        o = linear(prefix + "out_proj")
        softmax = by_name.get(prefix + "Softmax")
        producer = {o: n for n in g.node for o in n.output}
        scale_node = producer.get(softmax.input[0]) if softmax is not None else None
        if scale_node is not None and scale_node.op_type != "Div":
            scale_node = None
        if out is None or o is None or scale_node is None or softmax is None:
            continue
        scale = [const(i) for i in scale_node.input if const(i) is not None]
        # Heads and head size: the last two entries of a head-splitting
        # Reshape's target (constant, or a Concat whose last two are).
        split_shapes = []
        for r in ("Reshape", "Reshape_1", "Reshape_2"):
            target = by_name[prefix + r].input[1] if prefix + r in by_name else None
            if target is None:
                continue
            value = const(target)
            if value is None and target in producer and producer[target].op_type == "Concat":
                parts = [const(i) for i in producer[target].input]
                if len(parts) == 4 and all(p is not None for p in parts[2:]):
                    value = [-1, -1, int(parts[2].reshape(-1)[0]), int(parts[3].reshape(-1)[0])]
            if value is not None and len(value) == 4:
                split_shapes.append([int(d) for d in value])
        if len(scale) != 1 or not split_shapes:
            continue
        heads, dim = split_shapes[0][2], split_shapes[0][3]
        image_length = max(s[1] for s in split_shapes)
        scale = float(scale[0])
        w_o, b_o = o[1], o[2]
        width = heads * dim
        if w_o.shape[0] != width:
            continue
        q, k, v = (linear(prefix + n) for n in ("q_proj", "k_proj", "v_proj"))
        tag = "/semrec_attention/" + prefix.strip("/").replace("/", "_") + "/"
        built = Nodes(tag)
        node = built.add

        def init(name, value):
            new_inits[tag + name] = np.ascontiguousarray(value)
            return tag + name

        def shape(name, dims):
            return init(name, np.array(dims, np.int64))

        if prefix.endswith("_to_image/"):
            if q is None or k is None or v is None:
                continue  # keys/values projected in the image part already
            embed = k[1].shape[0]
            length = image_length
            if length <= 0:
                continue
            qp = node("Add", [node("MatMul", [q[0], init("w_q", q[1])], "q_mm"),
                              init("b_q", q[2])], "q")
            qh = node("Transpose", [node("Reshape", [qp, shape("s_qh", [1, -1, heads, dim])],
                                         "q_r")], "qh", perm=[0, 2, 1, 3])
            wkt = k[1].reshape(embed, heads, dim).transpose(1, 2, 0)[None]  # [1,H,D,E]
            qk = node("MatMul", [qh, init("w_k_t", wkt)], "qk")  # [1,H,T,E]
            qk_t = node("Reshape", [node("Transpose", [qk], "qk_t0", perm=[0, 3, 1, 2]),
                                    shape("s_qkt", [1, embed, -1])], "qk_t")  # [1,E,H*T]
            scores_t = node("MatMul", [k[0], qk_t], "scores_t")  # [1,L,H*T]
            scores = node("Reshape", [node("Transpose", [scores_t], "scores_t1", perm=[0, 2, 1]),
                                      shape("s_scores", [1, heads, -1, length])], "scores")
            attn = node("Softmax", [node("Div", [scores, init("scale", np.array(scale, np.float32))],
                                         "scaled")], "attn", axis=-1)
            ax = node("MatMul", [node("Reshape", [attn, shape("s_attn", [1, -1, length])],
                                      "attn_flat"), v[0]], "ax")  # [1,H*T,E]
            wv = v[1].reshape(embed, heads, dim).transpose(1, 0, 2)[None]  # [1,H,E,D]
            oh = node("Add", [node("MatMul", [node("Reshape", [ax, shape("s_axh", [1, heads, -1, embed])],
                                                   "axh"), init("w_v", wv)], "oh_mm"),
                              init("b_v", v[2].reshape(1, heads, 1, dim))], "oh")
            heads_out = node("Reshape", [node("Transpose", [oh], "o_t", perm=[0, 2, 1, 3]),
                                         shape("s_o", [1, -1, width])], "o")
            values = node("MatMul", [heads_out, init("w_o", w_o)], "out_mm")
        else:
            if k is None or v is None:
                continue
            embed = v[1].shape[0]
            kp = node("Add", [node("MatMul", [k[0], init("w_k", k[1])], "k_mm"),
                              init("b_k", k[2])], "k")
            kh = node("Transpose", [node("Reshape", [kp, shape("s_kh", [1, -1, heads, dim])],
                                         "k_r")], "kh", perm=[0, 2, 3, 1])  # [1,H,D,T]
            if q is not None:
                # scores = X (W_q k^T) / scale + b_q k^T / scale, [1, L, H*T]
                wq = (q[1] / scale).reshape(embed, heads, dim).transpose(1, 0, 2)[None]
                m = node("MatMul", [init("w_q", wq), kh], "m")  # [1,H,E,T]
                m_flat = node("Reshape", [node("Transpose", [m], "m_t", perm=[0, 2, 1, 3]),
                                          shape("s_m", [1, embed, -1])], "m_flat")
                bq = (q[2] / scale).reshape(1, heads, 1, dim)
                bias = node("Reshape", [node("MatMul", [init("b_q", bq), kh], "bias_h"),
                                        shape("s_bias", [1, 1, -1])], "bias")
                scores = node("Add", [node("MatMul", [q[0], m_flat], "scores_mm"), bias], "scores")
                length_shape = shape("s_lht", [1, 0, heads, -1])
                attn = node("Softmax", [node("Reshape", [scores, length_shape], "scores_h")],
                            "attn", axis=-1)  # [1,L,H,T]
                attn_flat = node("Reshape", [attn, shape("s_attn", [1, 0, -1])], "attn_flat")
            else:
                # The image part projected the queries: keep the scores, regroup.
                attn_flat = node("Reshape", [node("Transpose", [softmax.output[0]], "attn_t",
                                                  perm=[0, 2, 1, 3]),
                                             shape("s_attn", [1, 0, -1])], "attn_flat")
            vp = node("Add", [node("MatMul", [v[0], init("w_v", v[1])], "v_mm"),
                              init("b_v", v[2])], "v")
            vh = node("Transpose", [node("Reshape", [vp, shape("s_vh", [1, -1, heads, dim])],
                                         "v_r")], "vh", perm=[0, 2, 1, 3])  # [1,H,T,D]
            wo = w_o.reshape(heads, dim, w_o.shape[1])[None]  # [1,H,D,E']
            u = node("Reshape", [node("MatMul", [vh, init("w_o", wo)], "u_h"),
                                 shape("s_u", [1, -1, w_o.shape[1]])], "u")  # [1,H*T,E']
            values = node("MatMul", [attn_flat, u], "out_mm")
        node("Add", [values, init("b_o", b_o)], "out", out.output[0])
        replace_node(g, out, built.list)
        by_name = {n.name: n for n in g.node}
        count += 1
    if count:
        finish(g, new_inits)
    return count



UPSCALING = "/semrec_upscaling/"
SHAPE_OPS = ("Reshape", "Flatten", "Squeeze", "Unsqueeze", "Identity")
# Prompt part -> mask part tensors, and the prompt part's preview output.
MASK_PART_INPUTS = ("upscaling_tokens", "mask_hyper")
MASK_PART_OUTPUT = "block_logits"
PREVIEW = "mask_preview"


def split_mask_part(model):
    """Moves the mask upscaling (half the work per prompt) into a mask part.

    Automatic mask generation rejects most prompts' masks for their stability
    score, which needs the upscaled logits. The prompt part keeps the
    transformer, the IoU head and the decoder's choice among its candidate
    masks, and gains a preview: the chosen mask's logits at one of every 4x4
    low-res cells, computed exactly as the full upscaling would (each output
    cell of the two 2x2/stride-2 transposed convolutions depends on one
    token only): preview[y, x] = low_res_masks[4y + 2, 4x + 2]. The mask part
    computes the chosen mask's low-res logits from the prompt part's
    `upscaling_tokens` (any of them: [1, N, C] -> block_logits [1, N, 16])
    and `mask_hyper`, only for prompts worth it. Needs the
    structure rewrite_upscaling leaves, and the export's choice to be a Gather
    over the masks' axis (reached by shape-only ops). Returns the mask part and
    changes `model` into the prompt part, or returns None (model unchanged).
    """
    g = model.graph
    by_name = {n.name: n for n in g.node}
    names = ("mm1", "up1", "ln", "mm2", "up2", "hyper_t", "raster")
    if any(UPSCALING + k not in by_name for k in names):
        return None
    consumers = {}
    for n in g.node:
        for i in n.input:
            consumers.setdefault(i, []).append(n)
    inits = {i.name: numpy_helper.to_array(i) for i in g.initializer}
    tokens = by_name[UPSCALING + "mm1"].input[0]
    hyper = by_name[UPSCALING + "hyper_t"].input[0]  # [1, masks, channels]

    blocks = inits[by_name[UPSCALING + "blocks"].input[1]]  # [H, W, 2, 2, 2, 2, -1]
    height, width = int(blocks[0]), int(blocks[1])
    w1, b1 = inits[UPSCALING + "c_w1"], inits[UPSCALING + "c_b1"]
    w2, b2 = inits[UPSCALING + "c_w2"], inits[UPSCALING + "c_b2"]
    mid, channels = w1.shape[1] // 4, w2.shape[1] // 4

    # raster [1, masks, 16 HW] -(shape ops)-> [masks, ...] -Gather(choice)->
    # -(shape ops)-> low_res_masks [1, 1, 4H, 4W]: checked by running the
    # shape ops on numbered cells for each mask count that they accept.
    def follow(name, value):
        while True:
            users = consumers.get(name, [])
            if len(users) != 1 or users[0].op_type not in SHAPE_OPS:
                return name, users, value
            value = reshaped(users[0], value)
            name = users[0].output[0]

    def reshaped(n, value):
        if value is None:
            return None
        try:
            if n.op_type == "Reshape":
                shape = [d if d != 0 else value.shape[k] for k, d in enumerate(inits[n.input[1]])]
                return value.reshape(shape)
            if n.op_type == "Flatten":
                axis = attr(n, "axis", 1)
                return value.reshape(int(np.prod(value.shape[:axis])), -1)
            if n.op_type in ("Squeeze", "Unsqueeze"):
                axes = inits[n.input[1]] if len(n.input) > 1 else attr(n, "axes")
                if n.op_type == "Squeeze":
                    return np.squeeze(value, axis=tuple(int(a) for a in axes))
                return np.expand_dims(value, axis=tuple(int(a) for a in axes))
            return value  # Identity
        except (KeyError, ValueError, TypeError):
            return None

    cells = 16 * height * width
    raster = by_name[UPSCALING + "raster"].output[0]
    accepted = 0
    for masks in range(1, 9):
        numbered = np.arange(masks * cells).reshape(1, masks, cells)
        flat, users, value = follow(raster, numbered)
        if len(users) != 1 or users[0].op_type != "Gather" or attr(users[0], "axis", 0) != 0:
            return None
        gather = users[0]
        if gather.input[0] != flat:
            return None
        if value is None:
            continue  # a reshape for another mask count
        if value.shape[0] != masks or not np.array_equal(value.reshape(masks, cells), numbered[0]):
            return None
        end, users, low_res = follow(gather.output[0], value[:1])
        if (users or end != "low_res_masks" or low_res is None
                or low_res.shape != (1, 1, 4 * height, 4 * width)
                or not np.array_equal(low_res.reshape(-1), numbered[0, 0])):
            return None
        accepted += 1
    if not accepted:
        return None

    # The mask part: the upscaling nodes up to the logits, fed by its own
    # inputs, for any number of the tokens (the caller picks them: those near
    # the preview's boundary), each giving its 4 x 4 low-res cells in the
    # order (ky1, kx1, ky2, kx2): cell (4y + 2 ky1 + ky2, 4x + 2 kx1 + kx2).
    mask_nodes, needed, stop = [], {by_name[UPSCALING + "logits"].output[0]}, {tokens, hyper}
    for n in reversed(list(g.node)):
        if any(o in needed for o in n.output):
            mask_nodes.append(n)
            needed.update(i for i in n.input if i and i not in stop and i not in inits)
    mask_nodes = [copy.deepcopy(n) for n in reversed(mask_nodes)]
    rename = {tokens: MASK_PART_INPUTS[0], hyper: MASK_PART_INPUTS[1]}
    for n in mask_nodes:
        for k, i in enumerate(n.input):
            n.input[k] = rename.get(i, i)
    mask_nodes.append(helper.make_node("Reshape", [mask_nodes[-1].output[0], "c_blocks_shape"],
                                       [MASK_PART_OUTPUT], name=UPSCALING + "block_logits"))
    used = set(i for n in mask_nodes for i in n.input)
    mask_inits = [numpy_helper.from_array(v, k) for k, v in inits.items() if k in used]
    # Token counts free: the reshapes between the two upscalings take -1.
    for init in mask_inits:
        if init.name in (by_name[UPSCALING + "up1_px"].input[1],
                         by_name[UPSCALING + "features"].input[1]):
            shape = numpy_helper.to_array(init).copy()
            shape[1] = -1
            init.CopyFrom(numpy_helper.from_array(shape, init.name))
    mask_inits.append(numpy_helper.from_array(np.array([1, -1, 16], np.int64), "c_blocks_shape"))
    tokens_shape = [1, height * width, w1.shape[0]]
    mask_graph = helper.make_graph(
        mask_nodes, "sam_decoder_mask_part",
        [helper.make_tensor_value_info(MASK_PART_INPUTS[0], onnx.TensorProto.FLOAT,
                                       [1, "tokens", w1.shape[0]]),
         helper.make_tensor_value_info(MASK_PART_INPUTS[1], onnx.TensorProto.FLOAT,
                                       [1, 1, channels])],
        [helper.make_tensor_value_info(MASK_PART_OUTPUT, onnx.TensorProto.FLOAT,
                                       [1, "tokens", 16])],
        mask_inits)
    mask_part = helper.make_model(mask_graph, opset_imports=model.opset_import,
                                  producer_name="semrec split_sam_decoder.py")
    mask_part.ir_version = model.ir_version

    # The prompt part: the chosen mask's hypernetwork row, the tokens, the preview.
    ln = by_name[UPSCALING + "ln"]
    p = "/semrec_preview/"
    new_inits = {
        # Columns are (ky, kx, channel): block 3 = (1, 1) of the first
        # transposed convolution, block 0 = (0, 0) of the second.
        p + "c_w1": np.ascontiguousarray(w1[:, 3 * mid:]), p + "c_b1": b1[3 * mid:],
        p + "c_w2": np.ascontiguousarray(w2[:, :channels]), p + "c_b2": b2[:channels],
        p + "c_hyper_shape": np.array([1, 1, channels], np.int64),
        p + "c_shape": np.array([1, 1, height, width], np.int64),
        **gelu_constants(p),
    }
    built = Nodes(p)
    node, gelu = built.add, built.gelu

    chosen = node("Gather", [node("Flatten", [hyper], "hyper_flat", axis=2), gather.input[1]],
                  "hyper_chosen", axis=0)
    hyper_out = node("Reshape", [chosen, p + "c_hyper_shape"], "hyper", MASK_PART_INPUTS[1])
    if any(tokens in n.output for n in g.node):
        # The tokens' producer writes the output itself: an Identity would
        # copy 4 MB per prompt.
        for n in g.node:
            for io in (n.input, n.output):
                for k, name in enumerate(io):
                    if name == tokens:
                        io[k] = MASK_PART_INPUTS[0]
        tokens = MASK_PART_INPUTS[0]
    else:
        node("Identity", [tokens], "tokens", MASK_PART_INPUTS[0])
    a1 = node("Add", [node("MatMul", [tokens, p + "c_w1"], "mm1"), p + "c_b1"], "up1")
    n1 = node("LayerNormalization", [a1] + list(ln.input[1:]), "ln", axis=-1,
              epsilon=attr(ln, "epsilon"))
    a2 = node("Add", [node("MatMul", [gelu(n1, "gelu1"), p + "c_w2"], "mm2"), p + "c_b2"], "up2")
    logits = node("MatMul", [gelu(a2, "gelu2"),
                             node("Transpose", [hyper_out], "hyper_t", perm=[0, 2, 1])], "logits")
    node("Reshape", [logits, p + "c_shape"], "preview", PREVIEW)
    at = [k for k, n in enumerate(g.node) if n is gather][0]
    order = list(g.node[:at]) + built.list + list(g.node[at:])
    g.ClearField("node")
    g.node.extend(order)
    kept = [o for o in g.output if o.name != "low_res_masks"]
    g.ClearField("output")
    g.output.extend(kept + [
        helper.make_tensor_value_info(MASK_PART_INPUTS[0], onnx.TensorProto.FLOAT, tokens_shape),
        helper.make_tensor_value_info(MASK_PART_INPUTS[1], onnx.TensorProto.FLOAT,
                                      [1, 1, channels]),
        helper.make_tensor_value_info(PREVIEW, onnx.TensorProto.FLOAT, [1, 1, height, width])])
    finish(g, new_inits)
    return mask_part
