// A Foxglove client made of Foxglove's own libraries (@foxglove/ws-protocol's FoxgloveClient over
// ws, @foxglove/rosmsg + @foxglove/rosmsg2-serialization for CDR, @foxglove/rosmsg-msgs-common for
// the ROS 2 Humble definitions Foxglove publishes with), connected to `unav foxglove`:
//
//   node foxglove_client.mjs URL channels [WAIT_S]
//       prints every advertised channel as a JSON line {topic, schemaName} after WAIT_S seconds
//   node foxglove_client.mjs URL echo TOPIC N
//       subscribes and prints the first N decoded messages, one JSON line each
//       {receive_ns, message} (byte arrays as "<n bytes>", other typed arrays as lists)
//   node foxglove_client.mjs URL all SECONDS
//       subscribes to every advertised channel, parses each schema and decodes every message for
//       SECONDS; prints one JSON line {decoded: {topic: [schemaName, count]}, silent: [topics]}
//   node foxglove_client.mjs URL measure TOPIC SECONDS
//       subscribes, decodes every message and prints one JSON line: frames, frames/s, MB/s, and
//       the latency from the bridge's receive stamp to this client (p50/p95/max, ms); for a
//       CompressedImage channel checks each frame is a whole JPEG/PNG, for an Image its size
//   node foxglove_client.mjs URL teleop SETPOINT_TOPIC ODOM_TOPIC DX DY DZ MOVE_M TIMEOUT_S
//       publishes geometry_msgs/PoseStamped setpoints (start position + (DX, DY, DZ), start
//       attitude) at 5 Hz as Foxglove's Publish panel does, and exits 0 once the odometry has
//       moved MOVE_M towards it (one JSON line: start, end, distance moved, setpoints sent)
// Exit 1 (with the reason) on a refusal status, a schema or frame that does not decode, a timeout.
import WebSocket from "ws";
import wsProtocol from "@foxglove/ws-protocol";  // CommonJS: no named exports
const { FoxgloveClient } = wsProtocol;
import { parse } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import { ros2humble } from "@foxglove/rosmsg-msgs-common";

const [url, mode, ...args] = process.argv.slice(2);
const fail = (msg) => {
  console.error(`FAIL: ${msg}`);
  process.exit(1);
};
const nowNs = () => BigInt(Math.round((performance.timeOrigin + performance.now()) * 1e6));
const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
client.on("error", (e) => fail(`socket: ${e.message ?? e}`));
client.on("status", (s) => {
  if (s.level >= 2) fail(`server status: ${s.message}`);
  console.error(`status ${s.level}: ${s.message}`);
});
const channels = new Map();  // topic -> channel
const waiting = new Map();   // topic -> resolve
client.on("advertise", (list) => {
  for (const c of list) {
    channels.set(c.topic, c);
    waiting.get(c.topic)?.(c);
  }
});
const channelOf = (topic, timeoutS) =>
  channels.has(topic) ? Promise.resolve(channels.get(topic)) : new Promise((resolve, reject) => {
    waiting.set(topic, resolve);
    setTimeout(() => reject(new Error(`'${topic}' not advertised within ${timeoutS} s`)), 1000 * timeoutS);
  });
const readerOf = (c) => {
  if (c.encoding !== "cdr" || c.schemaEncoding !== "ros2msg") fail(`channel ${JSON.stringify(c)}`);
  try {
    return new MessageReader(parse(c.schema, { ros2: true }));
  } catch (e) {
    fail(`schema of ${c.schemaName} does not parse: ${e.message}`);
  }
};
const bytesOf = (view) => new Uint8Array(view.buffer, view.byteOffset, view.byteLength);
// The definitions Foxglove writes a ROS 2 type with: the type and every type nested in it.
const writerOf = (type) => {
  const defs = [];
  const add = (name) => {
    const d = ros2humble[name];
    if (!d) fail(`no ROS 2 Humble definition of ${name}`);
    if (defs.includes(d)) return;
    defs.push(d);
    for (const f of d.definitions) if (f.isComplex) add(f.type);
  };
  add(type);
  return new MessageWriter(defs);
};
const percentile = (xs, p) => xs.length ? [...xs].sort((a, b) => a - b)[Math.min(xs.length - 1, Math.floor(p * xs.length))] : NaN;

async function channelsMode(waitS) {
  await new Promise((r) => setTimeout(r, 1000 * Number(waitS ?? 3)));
  for (const c of channels.values()) console.log(JSON.stringify({ topic: c.topic, schemaName: c.schemaName }));
  process.exit(0);
}

async function echoMode(topic, count) {
  const c = await channelOf(topic, 60);
  const reader = readerOf(c);
  const plain = (k, v) => typeof v === "bigint" ? v.toString() : v instanceof Uint8Array ? `<${v.length} bytes>`
    : ArrayBuffer.isView(v) ? Array.from(v) : v;
  let received = 0;
  client.on("message", ({ timestamp, data }) => {
    let m;
    try {
      m = reader.readMessage(data);
    } catch (e) {
      fail(`message ${received} of ${topic} does not decode: ${e.message}`);
    }
    console.log(JSON.stringify({ receive_ns: timestamp.toString(), message: m }, plain));
    if (++received === Number(count)) process.exit(0);
  });
  client.subscribe(c.id);
}

async function allMode(seconds) {
  await new Promise((r) => setTimeout(r, 2000));  // the advertisements of the topics there are
  const bySubscription = new Map();
  for (const c of channels.values()) {
    const entry = { channel: c, reader: readerOf(c), count: 0 };
    bySubscription.set(client.subscribe(c.id), entry);
  }
  client.on("message", ({ subscriptionId, data }) => {
    const e = bySubscription.get(subscriptionId);
    try {
      e.reader.readMessage(data);
    } catch (err) {
      fail(`message ${e.count} of ${e.channel.topic} [${e.channel.schemaName}] does not decode: ${err.message}`);
    }
    ++e.count;
  });
  await new Promise((r) => setTimeout(r, 1000 * Number(seconds)));
  const decoded = {}, silent = [];
  for (const e of bySubscription.values()) {
    if (e.count) decoded[e.channel.topic] = [e.channel.schemaName, e.count];
    else silent.push(e.channel.topic);
  }
  console.log(JSON.stringify({ decoded, silent }));
  process.exit(0);
}

async function measureMode(topic, seconds) {
  const c = await channelOf(topic, 60);
  const reader = readerOf(c);
  const compressed = c.schemaName === "sensor_msgs/msg/CompressedImage";
  const latenciesMs = [];
  let frames = 0, bytes = 0, first = null, last = null, formats = new Set();
  client.on("message", ({ timestamp, data }) => {
    const arrived = nowNs();
    let m;
    try {
      m = reader.readMessage(data);
    } catch (e) {
      fail(`frame ${frames} of ${topic} does not decode: ${e.message}`);
    }
    if (compressed) {
      const d = m.data;
      const jpeg = d[0] === 0xff && d[1] === 0xd8 && d[d.length - 2] === 0xff && d[d.length - 1] === 0xd9;
      const png = d[0] === 0x89 && d[1] === 0x50 && d[2] === 0x4e && d[3] === 0x47;
      if (!(jpeg && m.format.includes("jpeg")) && !(png && m.format.includes("png")))
        fail(`frame ${frames}: format '${m.format}' but ${d.length} bytes starting ${d[0]} ${d[1]}`);
      formats.add(m.format);
    } else if (m.data !== undefined && m.step !== undefined && m.data.length !== m.step * m.height) {
      fail(`frame ${frames}: ${m.data.length} bytes for step ${m.step} x ${m.height} rows`);
    }
    if (first === null) first = arrived;
    last = arrived;
    ++frames;
    bytes += data.byteLength;
    latenciesMs.push(Number(arrived - timestamp) / 1e6);
  });
  client.subscribe(c.id);
  await new Promise((r) => setTimeout(r, 1000 * Number(seconds)));
  if (frames < 2) fail(`${frames} frames of ${topic} in ${seconds} s`);
  const span = Number(last - first) / 1e9;
  console.log(JSON.stringify({
    topic, schemaName: c.schemaName, formats: [...formats], frames,
    fps: +((frames - 1) / span).toFixed(2), mb_per_s: +(bytes / 1e6 / span).toFixed(3),
    bytes_per_frame: Math.round(bytes / frames),
    latency_ms: { p50: +percentile(latenciesMs, 0.5).toFixed(2), p95: +percentile(latenciesMs, 0.95).toFixed(2),
      max: +Math.max(...latenciesMs).toFixed(2) },
  }));
  process.exit(0);
}

async function teleopMode(setpointTopic, odomTopic, dx, dy, dz, moveM, timeoutS) {
  setTimeout(() => fail(`timeout after ${timeoutS} s: ${JSON.stringify(state)}`), 1000 * Number(timeoutS));
  const state = { start: null, now: null, target: null, sent: 0, moved: 0 };
  const odom = await channelOf(odomTopic, 60);
  const reader = readerOf(odom);
  let attitude = null;
  client.on("message", ({ data }) => {
    const m = reader.readMessage(data);
    const p = m.pose.pose.position;
    if (!state.start) {
      state.start = { x: p.x, y: p.y, z: p.z };
      state.target = { x: p.x + Number(dx), y: p.y + Number(dy), z: p.z + Number(dz) };
      attitude = m.pose.pose.orientation;
    }
    state.now = { x: p.x, y: p.y, z: p.z };
    const t = state.target, s = state.start;
    const len = Math.hypot(t.x - s.x, t.y - s.y, t.z - s.z);
    state.moved = ((p.x - s.x) * (t.x - s.x) + (p.y - s.y) * (t.y - s.y) + (p.z - s.z) * (t.z - s.z)) / len;
    if (state.moved >= Number(moveM)) {
      console.log(JSON.stringify(state));
      process.exit(0);
    }
  });
  client.subscribe(odom.id);
  const writer = writerOf("geometry_msgs/PoseStamped");
  const channel = client.advertise({ topic: setpointTopic, encoding: "cdr", schemaName: "geometry_msgs/msg/PoseStamped" });
  setInterval(() => {
    if (!state.target) return;
    const ms = Date.now();
    const msg = {
      header: { stamp: { sec: Math.floor(ms / 1000), nsec: (ms % 1000) * 1e6 }, frame_id: "world_ned" },
      pose: { position: state.target, orientation: attitude },
    };
    client.sendMessage(channel, writer.writeMessage(msg));
    ++state.sent;
  }, 200);
}

client.on("open", () => {
  const run = mode === "channels" ? channelsMode(...args) : mode === "measure" ? measureMode(...args)
    : mode === "all" ? allMode(...args) : mode === "echo" ? echoMode(...args)
    : mode === "teleop" ? teleopMode(...args) : Promise.reject(new Error(`unknown mode '${mode}'`));
  run.catch((e) => fail(e.message));
});
