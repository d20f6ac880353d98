"""The file contracts for Python scripts: the names of result fields, history columns and run.json
keys, read from docs/results-reference.json. The solver writes that file
(`tactus-solve results-reference --json`) and a test keeps it current, so a script that asks for a
name the solver does not declare fails here with the name, not later with a KeyError in a loop.
"""
import json
import os

_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_REF = json.load(open(os.path.join(_ROOT, "docs", "results-reference.json")))

POINT_FIELDS = {f["name"] for f in _REF["point_fields"]}
CELL_FIELDS = {f["name"] for f in _REF["cell_fields"]}
HISTORY_COLUMNS = list(_REF["history_columns"])
RUN_JSON_KEYS = set(_REF["run_json_keys"])
LABELS = dict(_REF["labels"])
SURFACE_GROUPS = dict(_REF["surface_groups"])


def _declared(name, names, what):
    if name not in names:
        raise KeyError(f"'{name}' is not a declared {what} (docs/results-reference.json)")
    return name


def point_field(name):
    return _declared(name, POINT_FIELDS, "point field")


def cell_field(name):
    return _declared(name, CELL_FIELDS, "cell field")


def history_column(name):
    return _declared(name, HISTORY_COLUMNS, "history.csv column")


def run_key(name):
    return _declared(name, RUN_JSON_KEYS, "run.json key")
