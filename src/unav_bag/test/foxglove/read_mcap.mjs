// Reads MCAP bags with the TypeScript libraries Foxglove itself uses (@mcap/core for the file, with
// CRC checks; @foxglove/rosmsg to parse each channel's ros2msg schema; @foxglove/rosmsg2-serialization
// to decode each CDR message; fzstd for zstd chunks) and checks what make_fixture_bags wrote:
//   node read_mcap.mjs BAGS_DIR
// BAGS_DIR/{mcap,mcap_zstd}: message i of /tf, /rov/odom, /rov/dvl, /rov/range, /rov/camera/image
// carries i in a known field; BAGS_DIR/all_types: two messages of every message type of interfaces/
// (one topic each). Exit status 1 on the first schema that does not parse or message that does not
// decode, with the channel, type and the parser's words.
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { decompress as zstdDecompress } from "fzstd";
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";

const decompressHandlers = {
  zstd: (data, size) => {
    const out = zstdDecompress(data);
    if (BigInt(out.length) !== size) throw new Error(`zstd chunk: ${out.length} bytes, expected ${size}`);
    return out;
  },
};

const fail = (msg) => {
  console.error(`FAIL: ${msg}`);
  process.exit(1);
};

const near = (a, b) => Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(b));

// What the fixture put into message i of each topic (make_fixture_bags.cpp).
const CHECKS = {
  "/tf": (m, i) => m.transforms.length === 1 && m.transforms[0].transform.translation.x === i &&
    m.transforms[0].header.frame_id === "map" && m.transforms[0].child_frame_id === "base_link",
  "/rov/odom": (m, i) => near(m.pose.pose.position.x, 0.5 * i) && m.pose.pose.orientation.w === 1,
  "/rov/dvl": (m, i) => near(m.velocity.x, 0.1 * i) && m.valid === true,
  "/rov/range": (m) => m.radiation_type === 1 && near(m.range, 1.5),
  "/rov/camera/image": (m, i) => m.width === 640 && m.height === 480 && m.encoding === "rgb8" &&
    m.data.length === 640 * 480 * 3 && m.data[0] === i % 251,
};

async function readBag(file) {
  const bytes = new Uint8Array(readFileSync(file));
  // The whole file as a stream first: every record and chunk CRC checked.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  let records = 0;
  for (let r; (r = stream.nextRecord()) !== undefined;) ++records;
  if (!stream.done()) fail(`${file}: the stream reader did not reach the footer`);
  // Then through the summary and index, as Foxglove opens a file.
  const reader = await McapIndexedReader.Initialize({
    readable: {
      size: async () => BigInt(bytes.length),
      read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
    },
    decompressHandlers,
  });
  const readers = new Map();
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    if (!schema || schema.encoding !== "ros2msg" || channel.messageEncoding !== "cdr")
      fail(`${file}: ${channel.topic}: schema encoding ${schema?.encoding}, message encoding ${channel.messageEncoding}`);
    try {
      readers.set(id, { topic: channel.topic, type: schema.name,
                        reader: new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })) });
    } catch (e) {
      fail(`${file}: ${channel.topic} (${schema.name}): the schema does not parse: ${e.message}`);
    }
  }
  const counts = new Map();
  for await (const msg of reader.readMessages()) {
    const r = readers.get(msg.channelId);
    const i = counts.get(r.topic) ?? 0;
    counts.set(r.topic, i + 1);
    let decoded;
    try {
      decoded = r.reader.readMessage(msg.data);
    } catch (e) {
      fail(`${file}: ${r.topic} (${r.type}) message ${i}: does not decode: ${e.message}`);
    }
    const check = CHECKS[r.topic];
    if (check && !check(decoded, i)) fail(`${file}: ${r.topic} message ${i}: ${JSON.stringify(decoded).slice(0, 300)}`);
  }
  return { records, channels: readers.size, counts, types: new Set([...readers.values()].map((r) => r.type)) };
}

const dir = process.argv[2];
if (!dir) fail("usage: node read_mcap.mjs BAGS_DIR");
for (const bag of ["mcap", "mcap_zstd", "all_types"]) {
  const files = readdirSync(join(dir, bag)).filter((f) => f.endsWith(".mcap"));
  if (files.length !== 1) fail(`${dir}/${bag}: ${files.length} .mcap files, expected 1`);
  const { records, channels, counts, types } = await readBag(join(dir, bag, files[0]));
  const expected = bag === "all_types" ? 2 : 10;
  for (const [topic, n] of counts) if (n !== expected) fail(`${bag}: ${topic}: ${n} messages, expected ${expected}`);
  if (counts.size !== channels) fail(`${bag}: ${channels} channels but messages on ${counts.size}`);
  const total = [...counts.values()].reduce((a, b) => a + b, 0);
  console.log(`${bag}: ${records} records, ${channels} channels (${types.size} types), ${total} messages decoded`);
}
console.log("foxglove readers: every schema parsed, every message decoded");
