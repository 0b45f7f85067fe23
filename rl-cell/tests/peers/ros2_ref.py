"""The ROS 2 reference for rl-cell's wire tests: PyPI rosbags' CDR serializer and RIHS01 type
hashes for ROS 2 Jazzy (rosbags.typesys.Stores.ROS2_JAZZY).

Reads one JSON object from stdin: {"hashes": [type names], "messages": [{"type": T, "msg": {...}}]}
and prints {"hashes": {T: "RIHS01_..."}, "cdr": ["hex", ...]} (little-endian CDR, with the
4-byte encapsulation header). A message is given as nested dicts of field values.
"""

import json
import sys

from rosmsg import build, store


def main():
    req = json.load(sys.stdin)
    out = {'hashes': {t: store.hash_rihs01(t) for t in req.get('hashes', [])}, 'cdr': []}
    for m in req.get('messages', []):
        msg = build(m['type'], m['msg'])
        out['cdr'].append(bytes(store.serialize_cdr(msg, m['type'], little_endian=True)).hex())
    json.dump(out, sys.stdout)


if __name__ == '__main__':
    main()
