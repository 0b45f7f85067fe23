"""A master not written here against our fake segment: pysoem (SOEM in a Python wheel).

Usage: python pysoem_check.py IFNAME [--dc] [--cycles N] [--bench N]
Prints one JSON object: what SOEM found and did. With --bench N it only reaches OP and times N
send_processdata + receive_processdata round trips at 1 ms (rtt_us), for
rl-drivers/examples/ecat_roundtrip.rs. Exit code 0 when it got that far; the Rust
test (tests/ecat_pysoem.rs) judges the values.
"""
import json
import struct
import sys
import time

import pysoem


def main():
    ifname = sys.argv[1]
    dc = "--dc" in sys.argv
    cycles = int(sys.argv[sys.argv.index("--cycles") + 1]) if "--cycles" in sys.argv else 500
    bench = int(sys.argv[sys.argv.index("--bench") + 1]) if "--bench" in sys.argv else 0
    out = {"soem": getattr(pysoem, "__version__", "?")}
    m = pysoem.Master()
    m.open(ifname)
    try:
        out["found"] = m.config_init()
        out["devices"] = [
            {"name": s.name, "vendor": s.man, "product": s.id, "revision": s.rev}
            for s in m.slaves
        ]
        if dc:
            out["dc"] = bool(m.config_dc())
            for s in m.slaves:
                s.dc_sync(True, 1_000_000)
        m.config_map()
        out["expected_wkc"] = m.expected_wkc
        out["safeop"] = m.state_check(pysoem.SAFEOP_STATE, 500_000) == pysoem.SAFEOP_STATE
        out["sizes"] = [[len(s.output), len(s.input)] for s in m.slaves]
        m.send_processdata()
        m.receive_processdata(2000)
        m.state = pysoem.OP_STATE
        m.write_state()
        op = False
        for _ in range(200):
            m.send_processdata()
            m.receive_processdata(2000)
            if m.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                op = True
                break
        out["op"] = op
        if bench:
            rtt, bad = [], 0
            next_t = time.monotonic()
            for _ in range(bench):
                t0 = time.perf_counter_ns()
                m.send_processdata()
                w = m.receive_processdata(2000)
                rtt.append((time.perf_counter_ns() - t0) / 1000.0)
                if w != m.expected_wkc:
                    bad += 1
                next_t += 0.001
                time.sleep(max(0.0, next_t - time.monotonic()))
            out["rtt_us"] = rtt
            out["wkc_errors"] = bad
            m.state = pysoem.INIT_STATE
            m.write_state()
            print(json.dumps(out))
            return
        # CSP: walk each drive to operation enabled (shutdown, switch on, enable operation)
        # with the target at the actual position, then move it 0.1 revolution.
        bad, wrong = 0, []
        start = [struct.unpack_from("<Hi", s.input, 0)[1] for s in m.slaves]
        next_t = time.monotonic()
        for k in range(cycles):
            for i, s in enumerate(m.slaves):
                cw = 0x06 if k < 20 else 0x07 if k < 40 else 0x0F
                target = start[i] + (k - 60) * 200 if k > 60 else start[i]
                s.output = struct.pack("<HiiHhbx", cw, target, 0, 0, 0, 8)
            t0 = time.perf_counter_ns()
            m.send_processdata()
            w = m.receive_processdata(2000)
            if w != m.expected_wkc:
                bad += 1
                # Which cycle, the count SOEM got (0 or less: no frame within the timeout) and
                # how long the round trip took, for the test to tell a lost frame from a wrong
                # count.
                wrong.append({"cycle": k, "wkc": w, "us": (time.perf_counter_ns() - t0) // 1000})
            next_t += 0.001
            time.sleep(max(0.0, next_t - time.monotonic()))
        out["wkc_errors"] = bad
        out["wkc_wrong"] = wrong
        out["cycles"] = cycles
        out["statusword"] = [struct.unpack_from("<H", s.input, 0)[0] for s in m.slaves]
        out["moved"] = [struct.unpack_from("<Hi", s.input, 0)[1] - start[i] for i, s in enumerate(m.slaves)]
        m.state = pysoem.INIT_STATE
        m.write_state()
    finally:
        m.close()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
