"""Reads TFLite flatbuffers with Python classes generated from TFLite's published schema.

The schema (`schema.fbs`, installed by scripts/setup like a model: sha256-checked) is compiled
with Debian's `flatc --python --gen-object-api` into a cache folder the first time, keyed by the
schema's checksum. Debian bookworm's flatc (2.0.8) predates the `(deprecated)` attribute on enum
values, union members and tables that newer schemas use; those attributes only mark names as
unused, so they are dropped before compiling (field attributes are kept: flatc knows them).
"""

import hashlib
import importlib
import os
import re
import shutil
import subprocess
import sys
import tempfile


class SchemaError(Exception):
    pass


def _compatible_schema(text):
    lines = []
    for line in text.split("\n"):
        code = line.split("//")[0]
        if ":" not in code:  # not a field declaration: an enum value, union member or table
            line = re.sub(r"\s*\(deprecated\)", "", line)
        lines.append(line)
    return "\n".join(lines)


def load(schema_path, cache_dir=None):
    """Returns the generated `tflite` package for `schema_path` (compiled once per checksum)."""
    try:
        with open(schema_path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SchemaError(f"{schema_path}: cannot read the TFLite schema ({e.strerror})")
    digest = hashlib.sha256(data).hexdigest()[:16]
    if cache_dir is None:
        cache_dir = os.path.join(os.path.dirname(os.path.abspath(schema_path)), "tflite_schema_py")
    target = os.path.join(cache_dir, digest)
    if not os.path.isfile(os.path.join(target, "tflite", "Model.py")):
        if shutil.which("flatc") is None:
            raise SchemaError("flatc not found (Debian package flatbuffers-compiler): "
                              "run scripts/setup")
        os.makedirs(cache_dir, exist_ok=True)
        tmp = tempfile.mkdtemp(dir=cache_dir)
        fbs = os.path.join(tmp, "schema.fbs")
        with open(fbs, "w") as f:
            f.write(_compatible_schema(data.decode("utf-8")))
        proc = subprocess.run(["flatc", "--python", "--gen-object-api", "-o", tmp, fbs],
                              capture_output=True, text=True)
        if proc.returncode != 0 or not os.path.isfile(os.path.join(tmp, "tflite", "Model.py")):
            shutil.rmtree(tmp, ignore_errors=True)
            raise SchemaError(f"{schema_path}: flatc could not compile it: "
                              f"{(proc.stderr or proc.stdout).strip()}")
        os.remove(fbs)
        try:
            os.rename(tmp, target)
        except OSError:  # another process compiled it meanwhile
            shutil.rmtree(tmp, ignore_errors=True)
    if target not in sys.path:
        sys.path.insert(0, target)
    return importlib.import_module("tflite")


def builtin_names(tflite):
    """Builtin operator code -> name (e.g. 3 -> 'CONV_2D')."""
    from tflite.BuiltinOperator import BuiltinOperator
    return {v: k for k, v in vars(BuiltinOperator).items() if not k.startswith("_")}


def read_model(tflite, path):
    """Parses a .tflite file into the object API (tflite.Model.ModelT)."""
    from tflite.Model import Model, ModelT
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SchemaError(f"{path}: cannot read ({e.strerror})")
    if len(data) < 8 or data[4:8] != b"TFL3":
        raise SchemaError(f"{path}: not a TFLite flatbuffer (no 'TFL3' identifier)")
    try:
        return ModelT.InitFromObj(Model.GetRootAsModel(data, 0))
    except Exception as e:  # a truncated or corrupt buffer raises from deep inside flatbuffers
        raise SchemaError(f"{path}: corrupt TFLite flatbuffer ({type(e).__name__}: {e})")


def op_code(model, op):
    code = model.operatorCodes[op.opcodeIndex]
    # Schema v3a: builtin_code (int32) replaced deprecated_builtin_code (int8) for codes >= 127.
    return max(code.builtinCode, code.deprecatedBuiltinCode)
