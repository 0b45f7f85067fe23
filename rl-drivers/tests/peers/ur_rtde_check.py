"""Reads our fake UR controller with PyPI ur-rtde 1.6.5 (SDU's ur_rtde, C++): its receive
interface at 500 Hz (every variable it asks for by default), its IO interface (digital
outputs, the speed slider, an analog output), and its dashboard client. Prints one JSON object.

Usage: ur_rtde_check.py HOST DASHBOARD_PORT SECONDS
ur_rtde connects to RTDE on port 30004 of HOST (it has no other).
"""
import json
import sys
import time

import dashboard_client
import rtde_io
import rtde_receive

host, dash_port, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
out = {}
r = rtde_receive.RTDEReceiveInterface(host, 500.0)
out["connected"] = r.isConnected()
stamps = []
walls = []  # when each new timestamp was first seen, s since t0
t0 = time.monotonic()
while time.monotonic() - t0 < seconds:
    t = r.getTimestamp()
    if not stamps or t != stamps[-1]:
        stamps.append(t)
        walls.append(time.monotonic() - t0)
    time.sleep(0.0002)
out["stamps"] = stamps
out["walls"] = walls
out["actual_q"] = list(r.getActualQ())
out["target_q"] = list(r.getTargetQ())
out["tcp_pose"] = list(r.getActualTCPPose())
out["robot_mode"] = r.getRobotMode()
out["safety_mode"] = r.getSafetyMode()
out["runtime_state"] = r.getRuntimeState()
out["joint_mode"] = list(r.getJointMode())
out["main_voltage"] = r.getActualMainVoltage()

io = rtde_io.RTDEIOInterface(host)
out["io"] = [
    io.setStandardDigitalOut(3, True),
    io.setConfigurableDigitalOut(1, True),
    io.setSpeedSlider(0.5),
    io.setAnalogOutputVoltage(0, 0.3),
]
time.sleep(0.1)
out["digital_out"] = r.getActualDigitalOutputBits()
out["speed_scaling"] = r.getSpeedScaling()
out["target_speed_fraction"] = r.getTargetSpeedFraction()
out["analog_out0"] = r.getStandardAnalogOutput0()
io.setStandardDigitalOut(3, False)
time.sleep(0.05)
out["digital_out_after"] = r.getActualDigitalOutputBits()
io.disconnect()

d = dashboard_client.DashboardClient(host, dash_port)
d.connect()
out["dashboard"] = {
    "connected": d.isConnected(),
    "robotmode": str(d.robotmode()),
    "polyscope": d.polyscopeVersion(),
    "remote": d.isInRemoteControl(),
    "running": d.running(),
}
d.disconnect()
r.disconnect()
print(json.dumps(out))
