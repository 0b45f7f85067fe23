"""A cell peer written against PyPI eclipse-zenoh and rosbags only (no rl-rs code): what a
tracking PC or a ROS 2 tool on another machine does.

  peer.py subscribe --connect EP --key KEYEXPR --out FILE [--duration S] [--idle S]
      Records every sample on KEYEXPR (JointState or String, decoded with rosbags) and every
      rmw_zenoh liveliness token of domain 0 coming and going, as JSON lines in FILE.
      Prints "ready" once subscribed. Ends after S seconds, or S idle seconds after the first
      sample, or when FILE.stop exists.

  peer.py publish --connect EP --plan PLAN.json
      Publishes the samples PLAN lists ({"key", "type", "msg", "sequence", "age_s", "gid",
      "after_s"}), each with rmw_zenoh's 33-byte attachment (sequence number, source
      timestamp now minus age_s, GID), after waiting after_s.
"""

import argparse
import collections
import json
import os
import struct
import sys
import threading
import time

import numpy as np
import zenoh

from rosmsg import build, store

TYPES = {
    'sensor_msgs::msg::dds_::JointState_': 'sensor_msgs/msg/JointState',
    'std_msgs::msg::dds_::String_': 'std_msgs/msg/String',
    'trajectory_msgs::msg::dds_::JointTrajectory_': 'trajectory_msgs/msg/JointTrajectory',
    'geometry_msgs::msg::dds_::PoseStamped_': 'geometry_msgs/msg/PoseStamped',
    'geometry_msgs::msg::dds_::PointStamped_': 'geometry_msgs/msg/PointStamped',
}


def session(args):
    conf = zenoh.Config()
    conf.insert_json5('mode', '"peer"')
    conf.insert_json5('scouting/multicast/enabled', 'false')
    conf.insert_json5('connect/endpoints', json.dumps(args.connect or []))
    conf.insert_json5('listen/endpoints', json.dumps(args.listen or []))
    return zenoh.open(conf)


def attachment(seq, ts, gid):
    return struct.pack('<qqB', seq, ts, 16) + gid


def decode(key, now, att, payload):
    """One recorded sample as a JSON-able dict: key, arrival, attachment, decoded message."""
    parts = key.split('/')
    typename = TYPES.get(parts[-2])
    rec = {'key': key, 'recv_ns': now}
    if att is not None and len(att) == 33:
        seq, ts, n = struct.unpack_from('<qqB', att)
        rec.update(seq=seq, ts=ts, gid=att[17:].hex(), gid_len=n)
    if typename:
        try:
            m = store.deserialize_cdr(payload, typename)
        except Exception as e:  # recorded for the test to fail on, with the bytes
            rec.update(error='%s: %s' % (type(e).__name__, e), payload_hex=payload.hex())
            return rec
        if typename == 'sensor_msgs/msg/JointState':
            # The IEEE 754 bits too: JSON readers may round decimal text by an ulp.
            bits = lambda a: [int(b) for b in np.asarray(a, dtype='<f8').view('<u8')]
            rec.update(stamp=[m.header.stamp.sec, m.header.stamp.nanosec], name=list(m.name),
                       position=m.position.tolist(), velocity=m.velocity.tolist(),
                       effort=m.effort.tolist(), position_bits=bits(m.position),
                       velocity_bits=bits(m.velocity), effort_bits=bits(m.effort))
        elif typename == 'std_msgs/msg/String':
            rec.update(text=m.data)
    return rec


def bounded(step, seconds=10.0):
    """Runs `step` (undeclaring or closing Zenoh) for at most `seconds`; whether it returned. A
    step that does not (a transport to a peer whose link was cut, in the netns test) is left
    behind on a daemon thread."""
    t = threading.Thread(target=step, daemon=True)
    t.start()
    t.join(seconds)
    return not t.is_alive()


def subscribe(args):
    out = open(args.out, 'w', buffering=1)
    s = session(args)
    state = {'first': None, 'last': time.monotonic()}
    # The callbacks only keep the bytes (in arrival order): decoding with rosbags at 1-2 kHz
    # on Zenoh's receive thread would make this peer the bottleneck that the publisher's
    # congestion control then drops for. The main loop decodes and writes every 20 ms.
    pending = collections.deque()

    def on_sample(sample):
        att = sample.attachment
        pending.append(('s', str(sample.key_expr), time.time_ns(),
                        att.to_bytes() if att is not None else None, sample.payload.to_bytes()))
        state['first'] = state['first'] or time.monotonic()
        state['last'] = time.monotonic()

    def on_token(sample):
        pending.append(('t', str(sample.key_expr), time.time_ns(), str(sample.kind), None))

    def flush():
        while pending:
            kind, key, now, extra, payload = pending.popleft()
            if kind == 's':
                rec = decode(key, now, extra, payload)
            else:
                rec = {'token': key, 'kind': extra, 'recv_ns': now}
            out.write(json.dumps(rec) + '\n')

    sub = s.declare_subscriber(args.key, on_sample)
    lv = s.liveliness().declare_subscriber('@ros2_lv/0/**', on_token, history=True)
    print('ready', flush=True)
    start = time.monotonic()
    while True:
        time.sleep(0.02)
        flush()
        now = time.monotonic()
        if now - start > args.duration or os.path.exists(args.out + '.stop'):
            break
        if state['first'] is not None and now - state['last'] > args.idle:
            break
    undeclared = bounded(lambda: (sub.undeclare(), lv.undeclare()))
    flush()
    out.close()
    if not (undeclared and bounded(s.close)):
        # Everything recorded is written; only Zenoh's teardown is left behind.
        print('peer.py: Zenoh did not undeclare or close within 10 s; exiting without it',
              file=sys.stderr, flush=True)
        os._exit(0)


def wait_for_peer(s, seconds=20.0):
    """Waits until the session has a peer (the endpoint it connects to may start listening
    after this script starts: a sample put before then goes nowhere); whether it has one."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if list(s.info.peers_zid()) or list(s.info.routers_zid()):
            return True
        time.sleep(0.05)
    return False


def publish(args):
    plan = json.load(open(args.plan))
    s = session(args)
    if args.connect and not wait_for_peer(s):
        print('peer.py: no peer at %s within 20 s; nothing published' % args.connect,
              file=sys.stderr, flush=True)
        os._exit(1)
    time.sleep(plan.get('settle_s', 1.0))
    pubs = {}
    for item in plan['samples']:
        time.sleep(item.get('after_s', 0.0))
        key = item['key']
        if key not in pubs:
            # Block, not the default Drop: a test peer that never loses what it was asked to
            # send, even when its send thread is kept off the CPU (a burst of samples).
            pubs[key] = s.declare_publisher(key, express=True,
                                            congestion_control=zenoh.CongestionControl.BLOCK)
        payload = bytes(store.serialize_cdr(build(item['type'], item['msg']), item['type'],
                                            little_endian=True))
        ts = time.time_ns() - int(item.get('age_s', 0.0) * 1e9)
        att = None
        if item.get('attachment', True):
            att = attachment(item['sequence'], ts, bytes.fromhex(item.get('gid', '11' * 16)))
        pubs[key].put(payload, attachment=att)
    time.sleep(plan.get('linger_s', 0.5))
    s.close()
    print('published', len(plan['samples']), flush=True)


def main():
    p = argparse.ArgumentParser()
    p.add_argument('mode', choices=['subscribe', 'publish'])
    p.add_argument('--connect', action='append')
    p.add_argument('--listen', action='append')
    p.add_argument('--key')
    p.add_argument('--out')
    p.add_argument('--plan')
    p.add_argument('--duration', type=float, default=60.0)
    p.add_argument('--idle', type=float, default=3.0)
    args = p.parse_args()
    (subscribe if args.mode == 'subscribe' else publish)(args)


if __name__ == '__main__':
    sys.exit(main())
