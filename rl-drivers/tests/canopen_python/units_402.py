"""python-canopen reads the factor group of rl-rs's fake CiA 402 drives by SDO (reached through
the PyPI python-can interface `can-cannelloni`): 0x608F position encoder resolution, 0x6091 gear
ratio, 0x6092 feed constant (sub-indices 1 and 2 each) and 0x6076 motor rated torque, for each
node given; an object the node lacks is reported with its SDO abort code. Prints one JSON
object {node: {object: [sub1, sub2] or abort code}}. Usage: units_402.py HOST:PORT EDS NODE..."""

import json
import sys

import canopen

address, eds, nodes = sys.argv[1], sys.argv[2], [int(n) for n in sys.argv[3:]]
out = {}
network = canopen.Network()
network.connect(interface="cannelloni", channel=address)
try:
    for node_id in nodes:
        node = network.add_node(node_id, eds)
        node.sdo.RESPONSE_TIMEOUT = 1.0
        seen = {}
        for index, subs in ((0x608F, (1, 2)), (0x6091, (1, 2)), (0x6092, (1, 2)), (0x6076, (0,))):
            try:
                seen[f"{index:#06x}"] = [
                    int.from_bytes(node.sdo.upload(index, s), "little") for s in subs
                ]
            except canopen.SdoAbortedError as e:
                seen[f"{index:#06x}"] = e.code
        out[str(node_id)] = seen
finally:
    network.disconnect()
print(json.dumps(out))
