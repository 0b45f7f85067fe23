"""The ROS 2 reference for rl-cell's wire tests: PyPI rosbags' CDR serializer and RIHS01 type
hashes for ROS 2 Jazzy (rosbags.typesys.Stores.ROS2_JAZZY).

Reads one JSON object from stdin: {"hashes": [type names], "messages": [{"type": T, "msg": {...}}]}
and prints {"hashes": {T: "RIHS01_..."}, "cdr": ["hex", ...]} (little-endian CDR, with the
4-byte encapsulation header). A message is given as nested dicts of field values.
"""

import json
import sys

import numpy as np
from rosbags.typesys import Stores, get_typestore

store = get_typestore(Stores.ROS2_JAZZY)


def build(typename, value):
    cls = store.types[typename]
    fields = store.fielddefs[typename][1]
    kwargs = {}
    for name, desc in fields:
        v = value[name]
        kind = desc[0]
        if kind == 2:  # a nested message
            kwargs[name] = build(desc[1], v)
        elif kind in (3, 4):  # an array or a sequence
            sub_kind, sub = desc[1][0]
            if sub_kind == 2:
                kwargs[name] = [build(sub, x) for x in v]
            elif sub[0] == 'string':
                kwargs[name] = list(v)
            else:
                kwargs[name] = np.array(v, dtype=np.float64 if sub[0] == 'float64' else None)
        else:
            kwargs[name] = v
    return cls(**kwargs)


def main():
    req = json.load(sys.stdin)
    out = {'hashes': {t: store.hash_rihs01(t) for t in req.get('hashes', [])}, 'cdr': []}
    for m in req.get('messages', []):
        msg = build(m['type'], m['msg'])
        out['cdr'].append(bytes(store.serialize_cdr(msg, m['type'], little_endian=True)).hex())
    json.dump(out, sys.stdout)


if __name__ == '__main__':
    main()
