"""A Robotiq-like gripper served by PyPI pymodbus's server, for our driver to talk to: pymodbus
parses our requests (framing, CRC, function codes) and answers them; a small model of the
gripper in the register action turns a write of the robot output into the status (activation
completes at once, the fingers are where they were asked). Logs every request pymodbus decoded.

Usage: pymodbus_server.py rtu PATH | tcp PORT
Prints "ready" once serving; serves until its standard input closes; then prints one JSON
object: the requests (function code, address, count, values) and the final registers.
"""
import asyncio
import json
import sys

from pymodbus.constants import ExcCodes
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice
from pymodbus.framer import FramerType

UNIT = 9
OUT, IN = 0x03E8, 0x07D0
output = [0] * 8
log = []


def status():
    act = (output[0] >> 8) & 1
    gto = (output[0] >> 11) & 1
    request = output[1] & 0xFF
    gsta = 3 if act else 0
    gobj = 3 if (act and gto) else 0
    byte0 = act | (gto << 3) | (gsta << 4) | (gobj << 6)
    position = request if (act and gto) else 0
    return [byte0 << 8, request, position << 8, 0, 0, 0, 0, 0]


async def action(function_code, start_address, address, count, current_registers, set_values):
    log.append([function_code, address, count, list(set_values) if set_values is not None else None])
    if set_values is not None and OUT <= address < OUT + 8:
        for k, v in enumerate(set_values):
            output[address - OUT + k] = int(v)
    if IN <= address < IN + 8:
        s = status()
        for k in range(count):
            current_registers[address - start_address + k] = s[address - IN + k]
    return None


device = SimDevice(
    id=UNIT,
    simdata=[
        SimData(OUT, count=8, values=0, datatype=DataType.REGISTERS),
        SimData(IN, count=8, values=0, datatype=DataType.REGISTERS),
    ],
    action=action,
)


async def main():
    if sys.argv[1] == "rtu":
        server = ModbusSerialServer(
            device, framer=FramerType.RTU, port=sys.argv[2], baudrate=115200, bytesize=8, parity="N", stopbits=1
        )
    else:
        server = ModbusTcpServer(device, address=("127.0.0.1", int(sys.argv[2])))
    task = asyncio.create_task(server.serve_forever())
    await asyncio.sleep(0.3)
    print("ready", flush=True)
    await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)
    await server.shutdown()
    task.cancel()
    print(json.dumps({"requests": log, "output": output, "status": status()}), flush=True)


asyncio.run(main())
