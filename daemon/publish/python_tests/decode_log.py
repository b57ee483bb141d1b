#!/usr/bin/env python3
"""Decodes livod's messages in an LCM log with the Python types lcm-gen generates at build time
(build/<preset>/generated/lcm/python on PYTHONPATH). Needs no LCM Python module: the generated
classes decode bytes with `struct`, and the log format (28-byte big-endian event headers) is read
here. Prints one line per event; exits 1 when an event has no known type.

    PYTHONPATH=build/release/generated/lcm/python python3 decode_log.py LOG
"""
import struct
import sys

import bot_core
import livod

TYPES = {
    t._get_packed_fingerprint(): t
    for t in (livod.pose_t, livod.health_t, livod.cloud_t, bot_core.pose_t)
}
SYNC = 0xEDA1DA01


def events(path):
    with open(path, "rb") as f:
        while True:
            header = f.read(28)
            if len(header) < 28:
                return
            sync, number, utime, channel_len, data_len = struct.unpack(">IqqII", header)
            if sync != SYNC:
                raise ValueError(f"bad sync word at event {number}")
            channel = f.read(channel_len).decode()
            yield channel, f.read(data_len)


def describe(message):
    if isinstance(message, livod.pose_t):
        return (f"sequence={message.sequence} status={message.status} "
                f"body_frame={message.body_frame} position={list(message.position)} "
                f"covariance00={message.covariance[0][0]}")
    if isinstance(message, bot_core.pose_t):
        return f"utime={message.utime} pos={list(message.pos)}"
    if isinstance(message, livod.health_t):
        return f"sensors={[s.name for s in message.sensors]} version={message.version}"
    points = [struct.unpack_from("<ffff", message.data, i * message.point_step)
              for i in range(message.num_points)]
    return f"fields={[f.name for f in message.fields]} num_points={message.num_points} last={points[-1]}"


def main():
    unknown = 0
    for channel, data in events(sys.argv[1]):
        decoder = TYPES.get(data[:8])
        if decoder is None:
            print(f"EVENT {channel} NO_TYPE")
            unknown += 1
            continue
        message = decoder.decode(data)
        print(f"EVENT {channel} {type(message).__module__} {describe(message)}")
    return 1 if unknown else 0


if __name__ == "__main__":
    sys.exit(main())
