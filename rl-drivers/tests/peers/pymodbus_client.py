"""Drives our fake Robotiq gripper with PyPI pymodbus's client, as an integrator's script would:
activation, a grasp with read/write multiple registers (0x17), single and multiple register
writes, reads of both maps, and the requests the gripper refuses. pymodbus checks our framing
and CRCs. Prints one JSON object.

Usage: pymodbus_client.py rtu PATH | tcp HOST PORT
"""
import json
import sys
import time

from pymodbus.client import ModbusSerialClient, ModbusTcpClient

UNIT = 9
OUT, IN = 0x03E8, 0x07D0

if sys.argv[1] == "rtu":
    client = ModbusSerialClient(
        port=sys.argv[2], baudrate=115200, bytesize=8, parity="N", stopbits=1, timeout=0.5, retries=0
    )
else:
    client = ModbusTcpClient(sys.argv[2], port=int(sys.argv[3]), timeout=0.5, retries=0)
assert client.connect(), "connect"
out = {"errors": []}


def check(r, what):
    if r.isError():
        out["errors"].append(f"{what}: {r}")
    return r


def status():
    r = check(client.read_input_registers(IN, count=3, device_id=UNIT), "read status")
    return r.registers


out["initial"] = status()
check(client.write_registers(OUT, [0x0000, 0, 0], device_id=UNIT), "reset")
check(client.write_registers(OUT, [0x0100, 0, 0], device_id=UNIT), "activate")
t0 = time.monotonic()
activating = status()
while (status()[0] >> 12) & 3 != 3:
    if time.monotonic() - t0 > 5:
        out["errors"].append("activation did not complete")
        break
    time.sleep(0.01)
out["activating"] = activating
out["activation_s"] = time.monotonic() - t0
out["activated"] = status()
# Close at full speed and force with one read/write transaction.
r = check(
    client.readwrite_registers(
        read_address=IN, read_count=3, write_address=OUT, values=[0x0900, 0x00FF, 0xFFFF], device_id=UNIT
    ),
    "read/write",
)
out["readwrite"] = r.registers
t0 = time.monotonic()
while (status()[0] >> 14) == 0:
    if time.monotonic() - t0 > 5:
        out["errors"].append("grasp did not complete")
        break
    time.sleep(0.01)
out["grasped"] = status()
out["grasp_s"] = time.monotonic() - t0
# Open with a single register write (position request 0).
check(client.write_register(OUT + 1, 0x0000, device_id=UNIT), "write single")
out["holding"] = check(client.read_holding_registers(OUT, count=3, device_id=UNIT), "read back").registers
# What the gripper refuses.
r = client.read_holding_registers(0x0000, count=1, device_id=UNIT)
out["outside_map"] = [r.isError(), getattr(r, "exception_code", None)]
r = client.read_coils(0, count=1, device_id=UNIT)
out["coils"] = [r.isError(), getattr(r, "exception_code", None)]
r = client.read_input_registers(IN + 4, count=8, device_id=UNIT)
out["past_the_map"] = [r.isError(), getattr(r, "exception_code", None)]
# Timing of one read over the line.
t0 = time.monotonic()
for _ in range(20):
    status()
out["read_ms"] = (time.monotonic() - t0) / 20 * 1000
client.close()
print(json.dumps(out))
