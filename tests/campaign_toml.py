"""Campaign documents as Python dicts, written out as TOML (for tests that mutate campaign values)."""

import json
import math

MISSING = object()  # a mutation that deletes the key


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(value)


def toml_document(doc: dict) -> str:
    """``doc``'s tables as [table] / [[table]]; values that are not tables as top-level keys."""
    top, blocks = [], []
    for key, value in doc.items():
        if isinstance(value, dict):
            blocks.append(f"[{key}]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in value.items()))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for entry in value:
                blocks.append(f"[[{key}]]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in entry.items()))
        else:
            top.append(f"{key} = {toml_value(value)}\n")
    return "".join(top) + "\n".join(blocks)


def mutate(doc, path: tuple, value):
    """A copy of ``doc`` with the value at ``path`` (keys and list indices) replaced, or deleted for MISSING."""
    doc = json.loads(json.dumps(doc))
    *parents, last = path
    node = doc
    for key in parents:
        node = node[key]
    if value is MISSING:
        del node[last]
    else:
        node[last] = value
    return doc


def paths(doc, prefix=()) -> list[tuple]:
    """Every key and list index of ``doc``, tables included."""
    out = []
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else ()
    for key, value in items:
        out.append((*prefix, key))
        out += paths(value, (*prefix, key))
    return out
