#!/usr/bin/env python3
"""Reads a limb session log (MCAP) with the official `mcap` reader and
prints, as one JSON object, the message count per topic, each channel's
schema name and encodings, and the first frame's keys.

    read_mcap.py FILE.mcap
"""
import json
import sys

from mcap.reader import make_reader


def main(path):
    counts, channels, first_frame = {}, {}, None
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        for schema, channel, message in reader.iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            channels[channel.topic] = {
                "schema": schema.name if schema else None,
                "schema_encoding": schema.encoding if schema else None,
                "message_encoding": channel.message_encoding,
            }
            if channel.topic == "/limb/frame" and first_frame is None:
                first_frame = list(json.loads(message.data).keys())
    stats = summary.statistics.message_count if summary and summary.statistics else None
    print(json.dumps({"counts": counts, "channels": channels, "first_frame_keys": first_frame,
                      "statistics_message_count": stats}))


if __name__ == "__main__":
    main(sys.argv[1])
