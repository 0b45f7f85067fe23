"""PyPI urx 0.11.0's real-time monitor (urx.urrtmon.URRTMonitor, port 30003) reads our fake
UR controller for a while; prints what it decoded as JSON.

Usage: urx_check.py HOST SECONDS
urx connects to HOST:30003 (the port is fixed in urx) and parses every message on its own
thread; its buffer keeps (receive time, controller time, tool vector, q actual) of each.
"""
import json
import sys
import time

from urx.urrtmon import URRTMonitor

host, seconds = sys.argv[1], float(sys.argv[2])
mon = URRTMonitor(host)
mon.start_buffering()
mon.start()
data = mon.get_all_data(wait=True)
time.sleep(seconds)
data = mon.get_all_data(wait=True)
buffer = mon.get_buffer()
mon.stop()
stamps = [float(b[1]) for b in buffer]
print(json.dumps({
    "messages": len(buffer),
    "ctrl_stamps": stamps,
    "q_actual": [float(x) for x in data["qActual"]],
    "q_target": [float(x) for x in data["qTarget"]],
    "tcp": [float(x) for x in data["tcp"]],
    "tcp_force": [float(x) for x in data["tcp_force"]],
}))
sys.stdout.flush()
