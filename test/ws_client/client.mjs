// SPDX-FileCopyrightText: 2026 fourws developers
// SPDX-License-Identifier: Apache-2.0
// A Foxglove WebSocket client for test/test_live_view.py: connects to a fourws live view,
// subscribes to the topics given, decodes every message with Foxglove's own libraries
// (@foxglove/ws-protocol, @foxglove/rosmsg, @foxglove/rosmsg2-serialization: what the Foxglove
// app uses for ROS 2 data) and prints one JSON line per message: {topic, log_time_ns, message}.
// It retries the connection until the server listens, and exits once it has `count` messages of
// the first topic or after `seconds`.
//
// usage: node client.mjs URL SECONDS COUNT TOPIC [TOPIC...]
import wsProtocol from "@foxglove/ws-protocol";
import { parse } from "@foxglove/rosmsg";
import serialization from "@foxglove/rosmsg2-serialization";

const { FoxgloveClient } = wsProtocol;
const { MessageReader } = serialization;
import WebSocket from "ws";

// the Foxglove SDK's server speaks the ws-protocol spec under the subprotocol name
// foxglove.sdk.v1 (it refuses the older foxglove.websocket.v1, which the client names)
const SUBPROTOCOL = "foxglove.sdk.v1";
const [url, seconds, count, ...topics] = process.argv.slice(2);
const deadline = Date.now() + Number(seconds) * 1000;
const wanted = new Set(topics);
const readers = new Map(); // subscription id -> {topic, reader}
let received = 0;

function plain(value) {
  if (typeof value === "bigint") return Number(value);
  if (ArrayBuffer.isView(value)) return Array.from(value, plain);
  if (Array.isArray(value)) return value.map(plain);
  if (value && typeof value === "object") {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, plain(v)]));
  }
  return value;
}

function connect() {
  const client = new FoxgloveClient({
    ws: new WebSocket(url, [SUBPROTOCOL]),
  });
  client.on("error", () => {
    if (Date.now() < deadline) setTimeout(connect, 200);
    else process.exit(3);
  });
  client.on("advertise", (channels) => {
    for (const channel of channels) {
      if (!wanted.has(channel.topic)) continue;
      if (channel.encoding !== "cdr" || channel.schemaEncoding !== "ros2msg") {
        console.error(`unexpected encoding of ${channel.topic}: ${channel.encoding}`);
        process.exit(4);
      }
      const reader = new MessageReader(parse(channel.schema, { ros2: true }));
      readers.set(client.subscribe(channel.id), { topic: channel.topic, reader });
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const sub = readers.get(subscriptionId);
    if (!sub) return;
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    const message = plain(sub.reader.readMessage(bytes));
    process.stdout.write(JSON.stringify({ topic: sub.topic, log_time_ns: Number(timestamp),
                                          message }) + "\n");
    if (sub.topic === topics[0] && ++received >= Number(count)) process.exit(0);
  });
}

setTimeout(() => process.exit(received > 0 ? 0 : 5), Number(seconds) * 1000);
connect();
