"""python-canopen's LocalNode, loaded from rl-rs's EDS, as a CiA 402 slave for rl-rs's
master: it connects to the master's cannelloni TCP endpoint (PyPI `can-cannelloni`), answers
SDO from its object dictionary (python-canopen's SDO server), obeys NMT, produces heartbeats
when 0x1017 is written (python-canopen's NmtSlave), and — the few lines of drive behaviour
python-canopen leaves to the application — applies the RPDO at each SYNC, runs the power state
machine from the controlword, follows the target position, and sends TPDO1 on each SYNC with
the mapping the master configured. Runs for SECONDS, then prints JSON with what it saw.
Usage: slave_402.py HOST:PORT NODE EDS SECONDS"""

import json
import sys
import time

import can
import canopen

address, node_id, eds, seconds = sys.argv[1], int(sys.argv[2]), sys.argv[3], float(sys.argv[4])

network = canopen.Network()
node = canopen.LocalNode(node_id, eds)
network.add_node(node)

seen = {"syncs": 0, "rpdos": 0, "tpdos": 0, "writes": [], "states": [], "nmt": []}
drive = {"state": 0x40, "cw": 0, "pos": 1234, "mapped": False, "pending": None}


def on_write(index, subindex, od, data):
    seen["writes"].append([index, subindex])
    if index == 0x6060:
        # The drive takes the mode at once and shows it in 0x6061.
        node.set_data(0x6061, 0, data, check_writable=False)


node.add_write_callback(on_write)
node.set_data(0x6064, 0, drive["pos"].to_bytes(4, "little", signed=True), check_writable=False)
node.set_data(0x6041, 0, drive["state"].to_bytes(2, "little"), check_writable=False)


def next_state(state, cw):
    """CiA 402 power state machine (transitions 2-10, 15), states by statusword bits."""
    if cw & 0x80 and state == 0x08:
        return 0x40
    if cw & 0x02 == 0:
        return 0x40
    if cw & 0x06 == 0x02:
        return 0x07 if state == 0x27 else 0x40
    cmd = cw & 0x0F
    if cmd in (0x06, 0x0E):
        return 0x21 if state in (0x40, 0x23, 0x27) else state
    if cmd == 0x07:
        return 0x23 if state in (0x21, 0x27) else state
    if cmd == 0x0F:
        return 0x27 if state in (0x21, 0x23) else state
    return state


def on_rpdo(pdo_map):
    seen["rpdos"] += 1
    drive["pending"] = {v.index: v.raw for v in pdo_map}


def on_sync(can_id, data, timestamp):
    if node.nmt.state != "OPERATIONAL":
        return
    seen["syncs"] += 1
    if not drive["mapped"]:
        # The master configured the PDOs by SDO; take its mapping.
        node.tpdo.read()
        node.rpdo.read()
        for m in node.rpdo.map.values():
            if m.enabled:
                m.add_callback(on_rpdo)
        drive["mapped"] = True
    # TPDO1: the values latched at this SYNC.
    tpdo = node.tpdo[1]
    for v in tpdo:
        if v.index == 0x6041:
            v.raw = drive["state"] | 0x0210 if drive["state"] in (0x21, 0x23, 0x27, 0x07) else drive["state"] | 0x0200
        elif v.index == 0x6064:
            v.raw = drive["pos"]
        else:
            v.raw = 0
    tpdo.transmit()
    seen["tpdos"] += 1
    # The RPDO received since the last SYNC takes effect now.
    p = drive["pending"]
    drive["pending"] = None
    if p is not None:
        cw = p.get(0x6040, drive["cw"])
        new = next_state(drive["state"], cw)
        if new != drive["state"]:
            seen["states"].append(new)
        if new == 0x27 and 0x607A in p:
            drive["pos"] = p[0x607A]
        drive["state"], drive["cw"] = new, cw


network.subscribe(0x80, on_sync)
# Everything is in place before the master can send its first request.
deadline = time.monotonic() + 20
while True:
    try:
        network.connect(interface="cannelloni", channel=address, reconnect=False)
        break
    except can.CanError:
        if time.monotonic() > deadline:
            raise
        time.sleep(0.05)

end = time.monotonic() + seconds
while time.monotonic() < end:
    time.sleep(0.01)
seen["nmt_final"] = node.nmt.state
seen["tpdo1_mapping"] = [node.sdo[0x1A00][s].raw for s in range(0, node.sdo[0x1A00][0].raw + 1)]
seen["rpdo1_mapping"] = [node.sdo[0x1600][s].raw for s in range(0, node.sdo[0x1600][0].raw + 1)]
seen["heartbeat_ms"] = node.sdo[0x1017].raw
seen["mode"] = node.sdo[0x6060].raw
seen["position"] = drive["pos"]
network.disconnect()
print(json.dumps(seen))
