#!/usr/bin/python3
"""Runs a quantized TFLite segmenter with Arm NN (Debian's python3-pyarmnn, CpuRef backend).

    armnn_reference.py MODEL.tflite --schema schema.fbs IN.rgb OUT.labels [IN.rgb OUT.labels ...]

An independent reference for scripts/tflite_to_onnx.py: Arm NN executes the quantized graph in
integer arithmetic, as TFLite does. IN.rgb holds H*W*3 bytes (RGB, row-major, the model's input
size); OUT.labels receives H*W little-endian uint16 class ids and OUT.labels.margin H*W bytes:
how many quantization steps the winning logit leads the runner-up by (0 = a tie, capped at 255).
A float conversion cannot follow the quantized graph's rounding where the margin is small. Arm NN 22 has no ARG_MAX, so the
graph's final ARG_MAX is removed here and the argmax is taken over the uint8 logits (ties go to
the lowest class id, as TFLite's ARG_MAX does). CpuRef is slow (about a minute per 512x512 image
on one core): it belongs in a check, not at run time. Exit status: 0 done, 1 error.
"""

import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tflite_schema  # noqa: E402


def without_final_argmax(tfl, model, path):
    import flatbuffers
    graph = model.subgraphs[0]
    names = tflite_schema.builtin_names(tfl)
    last = graph.operators[-1]
    if names.get(tflite_schema.op_code(model, last)) != "ARG_MAX":
        raise RuntimeError(f"{path}: the graph does not end in ARG_MAX")
    graph.outputs = [last.inputs[0]]
    graph.operators = graph.operators[:-1]
    builder = flatbuffers.Builder(0)
    builder.Finish(model.Pack(builder), file_identifier=b"TFL3")
    return bytes(builder.Output())


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("tflite")
    parser.add_argument("--schema", required=True)
    parser.add_argument("pairs", nargs="+", help="IN.rgb OUT.labels pairs")
    args = parser.parse_args(argv)
    if len(args.pairs) % 2:
        parser.error("inputs and outputs come in pairs")
    try:
        import pyarmnn as ann
    except ImportError:
        print("armnn_reference: python3-pyarmnn is not installed (scripts/setup installs it)",
              file=sys.stderr)
        return 1
    try:
        tfl = tflite_schema.load(args.schema)
        model = tflite_schema.read_model(tfl, args.tflite)
        data = without_final_argmax(tfl, model, args.tflite)
    except (tflite_schema.SchemaError, RuntimeError) as e:
        print(f"armnn_reference: error: {e}", file=sys.stderr)
        return 1
    with tempfile.NamedTemporaryFile(suffix=".tflite") as f:
        f.write(data)
        f.flush()
        parser_ = ann.ITfLiteParser()
        network = parser_.CreateNetworkFromBinaryFile(f.name)
    in_info = parser_.GetNetworkInputBindingInfo(0, parser_.GetSubgraphInputTensorNames(0)[0])
    out_info = parser_.GetNetworkOutputBindingInfo(0, parser_.GetSubgraphOutputTensorNames(0)[0])
    runtime = ann.IRuntime(ann.CreationOptions())
    try:
        optimized, _ = ann.Optimize(network, [ann.BackendId("CpuRef")], runtime.GetDeviceSpec(),
                                    ann.OptimizerOptions())
    except RuntimeError as e:
        print(f"armnn_reference: Arm NN has no CpuRef backend ({e}); install Debian's "
              "libarmnn-cpuref-backend22", file=sys.stderr)
        return 1
    net_id, _ = runtime.LoadNetwork(optimized)
    shape = list(in_info[1].GetShape())
    h, w = shape[1], shape[2]
    for src, dst in zip(args.pairs[0::2], args.pairs[1::2]):
        rgb = np.fromfile(src, dtype=np.uint8)
        if rgb.size != h * w * 3:
            print(f"armnn_reference: error: {src}: {rgb.size} bytes, expected {h}x{w}x3 = "
                  f"{h * w * 3}", file=sys.stderr)
            return 1
        inputs = ann.make_input_tensors([in_info], [rgb.reshape(1, h, w, 3)])
        outputs = ann.make_output_tensors([out_info])
        runtime.EnqueueWorkload(net_id, inputs, outputs)
        logits = ann.workload_tensors_to_ndarray(outputs)[0].reshape(h, w, -1)
        labels = np.argmax(logits, axis=-1).astype("<u2")
        top2 = np.sort(logits.astype(np.int32), axis=-1)[..., -2:]
        margin = np.minimum(top2[..., 1] - top2[..., 0], 255).astype(np.uint8)
        for data, path in ((margin, dst + ".margin"), (labels, dst)):
            data.tofile(path + ".tmp")
            os.replace(path + ".tmp", path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
