"""Reads our fake Net F/T with two clients not written here, PyPI `pynetft` 2.1.3 (C++ core:
calibration from the sensor's netftapi2.xml over HTTP, RDT streaming, its own loss, order and
repeat counts) and PyPI `netft` 2.0.1 (plain RDT, counts). Prints one JSON object.

Usage: netft_check.py HOST RDT_PORT HTTP_PORT
Protocol with the test on stdin/stdout: prints "ready" once pynetft streams, waits for a line
on stdin (the test injects faults meanwhile), reads 0.3 s more, biases the sensor, reads until
the biased records come (3 s at most), stops, prints the JSON of pynetft's part, waits for a line (the test changes the load),
reads one record with `netft` (only if RDT_PORT is 49152: `netft` knows no other) and prints
its JSON.
"""
import json
import sys
import time

import NetFT
import pynetft

host, rdt_port, http_port = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])

client = pynetft.Client(pynetft.Config(sensor_host=host, rdt_port=rdt_port, http_port=http_port))
client.start()
if not client.wait_for_first_sample(2.0):
    print(json.dumps({"error": "pynetft: no first sample"}))
    sys.exit(1)
first = client.latest_sample()
print("ready", flush=True)
sys.stdin.readline()
time.sleep(0.3)
loaded = client.latest_sample()
health = client.health()
client.bias()
# Records sent before the bias may still wait in the socket's buffer (7000 a second; a
# loaded machine delays pynetft's reader): read until the biased ones come, for 3 s at most.
deadline = time.monotonic() + 3.0
while True:
    time.sleep(0.05)
    biased = client.latest_sample()
    if all(abs(x) < 1e-6 for x in biased.wrench) or time.monotonic() > deadline:
        break
client.stop()

cal = health.sensor_configuration.calibration
out = {
    "calibration": {
        "counts_per_force": cal.counts_per_force_unit,
        "counts_per_torque": cal.counts_per_torque_unit,
        "force_unit": cal.force_unit.value,
        "torque_unit": cal.torque_unit.value,
    },
    "first_wrench": list(first.wrench),
    "loaded_wrench": list(loaded.wrench),
    "biased_wrench": list(biased.wrench),
    "health": {
        "state": health.state.value,
        "fault_code": health.fault_code.value,
        "received_count": health.received_count,
        "lost_count": health.lost_count,
        "duplicate_count": health.duplicate_count,
        "out_of_order_count": health.out_of_order_count,
        "malformed_count": health.malformed_count,
        "device_error_count": health.device_error_count,
        "receive_rate_hz": health.receive_rate_hz,
    },
}

print(json.dumps(out), flush=True)
sys.stdin.readline()
# `netft` always talks to port 49152.
netft = {}
if rdt_port == 49152:
    sensor = NetFT.Sensor(host)
    sensor.sock.settimeout(2.0)
    netft["counts"] = list(sensor.getMeasurement())
    sensor.sock.close()
print(json.dumps(netft), flush=True)
