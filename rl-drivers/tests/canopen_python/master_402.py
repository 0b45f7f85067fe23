"""python-canopen as the master of rl-rs's fake CiA 402 drive (reached through the PyPI
python-can interface `can-cannelloni`, a cannelloni TCP client): reads the identity and objects
by SDO (expedited and segmented), provokes an SDO abort, configures TPDO1 and RPDO1, starts NMT
and SYNC, and walks the drive to OPERATION ENABLED with python-canopen's BaseNode402. Prints
one JSON object with what it saw. Usage: master_402.py HOST:PORT NODE EDS"""

import json
import sys
import time

import canopen

address, node_id, eds = sys.argv[1], int(sys.argv[2]), sys.argv[3]
out = {}
network = canopen.Network()
network.connect(interface="cannelloni", channel=address)
try:
    node = canopen.BaseNode402(node_id, eds)
    network.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 1.0
    out["device_type"] = node.sdo[0x1000].raw
    out["vendor_id"] = node.sdo[0x1018][1].raw
    out["product_code"] = node.sdo[0x1018][2].raw
    out["serial"] = node.sdo[0x1018][4].raw
    out["device_name"] = node.sdo[0x1008].raw  # 24 bytes: a segmented upload
    out["supported_modes"] = node.sdo[0x6502].raw
    node.sdo[0x6065].raw = 123456  # expedited download
    out["following_window"] = node.sdo[0x6065].raw
    try:
        node.sdo.upload(0x2000, 0)
        out["abort"] = None
    except canopen.SdoAbortedError as e:
        out["abort"] = e.code
    try:
        node.sdo[0x6041].raw = 5
        out["read_only_abort"] = None
    except canopen.SdoAbortedError as e:
        out["read_only_abort"] = e.code

    node.nmt.state = "PRE-OPERATIONAL"
    node.tpdo.read()
    node.rpdo.read()
    tpdo = node.tpdo[1]
    tpdo.clear()
    tpdo.add_variable(0x6041)
    tpdo.add_variable(0x6064)
    tpdo.trans_type = 1
    tpdo.enabled = True
    rpdo = node.rpdo[1]
    rpdo.clear()
    rpdo.add_variable(0x6040)
    rpdo.add_variable(0x607A)
    rpdo.trans_type = 255
    rpdo.enabled = True
    node.tpdo.save()
    node.rpdo.save()
    out["tpdo1_mapping"] = [node.sdo[0x1A00][s].raw for s in range(0, 3)]
    out["tpdo1_cob_id"] = node.sdo[0x1800][1].raw
    node.sdo[0x6060].raw = 8
    node.setup_402_state_machine(read_pdos=True)

    node.nmt.state = "OPERATIONAL"
    network.sync.start(0.01)
    node.tpdo[1].wait_for_reception(1.0)
    out["state_before"] = node.state
    rpdo["Target position"].raw = node.tpdo_values[0x6064]
    node.state = "OPERATION ENABLED"
    node.tpdo[1].wait_for_reception(1.0)
    out["state_enabled"] = node.state
    out["statusword_sdo"] = node.sdo[0x6041].raw
    node.state = "SWITCH ON DISABLED"
    node.tpdo[1].wait_for_reception(1.0)
    out["state_after"] = node.state
    network.sync.stop()
    node.nmt.state = "PRE-OPERATIONAL"
finally:
    network.disconnect()
print(json.dumps(out))
