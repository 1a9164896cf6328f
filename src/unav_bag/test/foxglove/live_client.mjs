// A Foxglove WebSocket client made of what Foxglove itself uses (ws for the socket,
// @foxglove/rosmsg for the advertised ros2msg schema, @foxglove/rosmsg2-serialization for the CDR
// frames): connects to `unav foxglove`, waits for TOPIC to be advertised, subscribes, decodes the
// first N messages and prints each as one JSON line. Exit 1 (with the reason) when the server
// refuses, the topic never comes, a schema does not parse or a frame does not decode.
//   node live_client.mjs ws://127.0.0.1:8765 /rov/ground_truth/odom [N] [TIMEOUT_S]
import WebSocket from "ws";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const [url, topic, countArg, timeoutArg] = process.argv.slice(2);
const count = Number(countArg ?? 3);
const fail = (msg) => {
  console.error(`FAIL: ${msg}`);
  process.exit(1);
};
setTimeout(() => fail(`timeout: ${received} of ${count} messages of ${topic}`), 1000 * Number(timeoutArg ?? 60));

let received = 0;
let reader = null;
const subscriptionId = 42;
const ws = new WebSocket(url, ["foxglove.websocket.v1"]);
ws.binaryType = "nodebuffer";
ws.on("error", (e) => fail(`socket: ${e.message}`));
ws.on("message", (data, isBinary) => {
  if (!isBinary) {
    const msg = JSON.parse(data.toString());
    if (msg.op === "serverInfo" && ws.protocol !== "foxglove.websocket.v1") fail(`subprotocol '${ws.protocol}'`);
    if (msg.op !== "advertise" || reader) return;
    const ch = msg.channels.find((c) => c.topic === topic);
    if (!ch) return;
    if (ch.encoding !== "cdr" || ch.schemaEncoding !== "ros2msg") fail(`channel ${JSON.stringify(ch)}`);
    try {
      reader = new MessageReader(parse(ch.schema, { ros2: true }));
    } catch (e) {
      fail(`schema of ${ch.schemaName} does not parse: ${e.message}`);
    }
    console.error(`advertised: ${topic} [${ch.schemaName}] channel ${ch.id}`);
    ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: subscriptionId, channelId: ch.id }] }));
    return;
  }
  if (data[0] !== 0x01) return;  // Message Data
  const sub = data.readUInt32LE(1);
  if (sub !== subscriptionId) fail(`frame for subscription ${sub}`);
  const receiveNs = data.readBigUInt64LE(5);
  let m;
  try {
    m = reader.readMessage(data.subarray(13));
  } catch (e) {
    fail(`frame ${received} does not decode: ${e.message}`);
  }
  // Byte arrays (image data) as their length, other typed arrays (covariances) as lists.
  const plain = (k, v) => typeof v === "bigint" ? v.toString() : v instanceof Uint8Array ? `<${v.length} bytes>`
    : ArrayBuffer.isView(v) ? Array.from(v) : v;
  console.log(JSON.stringify({ receive_ns: receiveNs.toString(), message: m }, plain));
  if (++received === count) {
    ws.close();
    process.exit(0);
  }
});
