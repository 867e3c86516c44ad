#!/usr/bin/python3
"""Test helper: copies a .tflite whose first operator code is relabelled TANH.

    edit_tflite_opcode.py IN.tflite OUT.tflite --schema schema.fbs

Used to check that scripts/tflite_to_onnx.py names an operator it does not support.
"""
import argparse
import os
import sys

import flatbuffers

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                "scripts"))
import tflite_schema  # noqa: E402

args = argparse.ArgumentParser()
args.add_argument("src")
args.add_argument("dst")
args.add_argument("--schema", required=True)
a = args.parse_args()
tfl = tflite_schema.load(a.schema)
from tflite.BuiltinOperator import BuiltinOperator  # noqa: E402

model = tflite_schema.read_model(tfl, a.src)
code = model.operatorCodes[model.subgraphs[0].operators[0].opcodeIndex]
code.builtinCode = BuiltinOperator.TANH
code.deprecatedBuiltinCode = BuiltinOperator.TANH
builder = flatbuffers.Builder(0)
builder.Finish(model.Pack(builder), file_identifier=b"TFL3")
with open(a.dst, "wb") as f:
    f.write(builder.Output())
