"""Compares gfuzzy's Foxglove schemas (gfuzzy/export/foxglove.py) with Foxglove's own JSON Schema
files, and validates the messages of MCAP files against Foxglove's files.

    python tools/check_foxglove_schemas.py SCHEMAS_DIR [FILE.mcap ...]

SCHEMAS_DIR: ``schemas/jsonschema`` of a checkout of the foxglove/schemas repository (not
shipped with gfuzzy). Prints, per message, the fields one side has and the other lacks and
the fields whose JSON types differ, then how many messages validated; exits 1 on any
difference or invalid message.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import jsonschema

from gfuzzy.export.foxglove import SCHEMAS


def fields(schema: dict, path: str = "") -> dict:
    """Dotted field path -> JSON type, through nested objects and arrays."""
    out: dict = {}
    if schema.get("type") == "object" and "properties" in schema:
        for key, sub in schema["properties"].items():
            out[f"{path}.{key}"] = sub.get("type")
            out.update(fields(sub, f"{path}.{key}"))
    if schema.get("type") == "array":
        out.update(fields(schema["items"], f"{path}[]"))
    return out


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__)
        return 2
    folder = Path(argv[0])
    upstream = {name: json.loads((folder / f"{name.split('.')[1]}.json").read_text()) for name in SCHEMAS}
    bad = 0
    for name, theirs in upstream.items():
        mine_f, theirs_f = fields(SCHEMAS[name]), fields(theirs)
        only_mine = sorted(set(mine_f) - set(theirs_f))
        only_theirs = sorted(k for k in set(theirs_f) - set(mine_f) if ".models[]." not in k)
        types = sorted(k for k in set(mine_f) & set(theirs_f) if mine_f[k] != theirs_f[k])
        print(f"{name}: {len(mine_f)} fields; only gfuzzy's: {only_mine}; only Foxglove's: {only_theirs}; types differ: {types}")
        bad += len(only_mine) + len(only_theirs) + len(types)
    if len(argv) > 1:
        from mcap.reader import make_reader

        validators = {name: jsonschema.Draft7Validator(s) for name, s in upstream.items()}
        count = 0
        for file in argv[1:]:
            with open(file, "rb") as fh:
                for schema, _, message in make_reader(fh).iter_messages():
                    errors = list(validators[schema.name].iter_errors(json.loads(message.data)))
                    bad += len(errors)
                    count += 1
        print(f"{count} messages validated against Foxglove's schemas, {bad} problems")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
