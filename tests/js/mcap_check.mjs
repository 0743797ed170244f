// Reads the files of telegrasp-mcap-sample (tests/client_lib/tools/mcap/mcap_sample.cc) with the reference
// TypeScript MCAP reader, @mcap/core, and checks them against the sample's JSON sidecar:
//   sample.mcap      McapIndexedReader (footer, summary CRC, statistics, chunk indexes, summary
//                    offsets, messages through the message indexes with chunk CRCs) and
//                    McapStreamReader (every record in file order, chunk CRCs), plus the data
//                    section CRC recomputed here; counts and time ranges per channel.
//   sample_cut.mcap  McapStreamReader gets every message of the chunks before the cut, then ends
//                    cleanly (waits for more bytes) or throws; never a wrong message.
//   sample_killed.mcap  the same for the file as a killed recorder leaves it (no summary, no
//                    footer, ends after its last complete chunk).
// Usage: node tests/js/mcap_check.mjs SAMPLE_DIR   (run by ctest as mcap.reference_reader)
import fs from "node:fs";
import path from "node:path";
import { McapIndexedReader, Opcode, crc32, decompressHandlers, readableOf, streamRecords } from "./mcap_common.mjs";

let failures = 0;
let passes = 0;
function check(ok, what) {
  if (ok) {
    passes++;
  } else {
    failures++;
    console.error(`FAIL: ${what}`);
  }
}
function fatal(what) {
  console.error(`mcap_check: ${what}`);
  process.exit(1);
}

const dir = process.argv[2];
if (!dir) fatal("usage: node mcap_check.mjs SAMPLE_DIR");
const expected = JSON.parse(fs.readFileSync(path.join(dir, "sample.json"), "utf8"));

// Per-topic tally of messages: count, first and last log time, sequences in order.
class Tally {
  constructor() {
    this.byTopic = new Map();
    this.total = 0;
    this.lastLogTime = undefined;
  }
  add(topic, message, where) {
    let t = this.byTopic.get(topic);
    if (!t) {
      t = { count: 0, start: message.logTime, end: message.logTime };
      this.byTopic.set(topic, t);
    }
    // The sample numbers each channel's messages 0, 1, 2, ... in the record and in the JSON.
    if (message.sequence !== t.count) {
      check(false, `${where}: ${topic} message ${t.count} has sequence ${message.sequence}`);
    }
    const json = JSON.parse(new TextDecoder().decode(message.data));
    if (json.seq !== message.sequence) {
      check(false, `${where}: ${topic} JSON seq ${json.seq} != record sequence ${message.sequence}`);
    }
    if (message.publishTime !== message.logTime + BigInt(expected.publish_time_offset_ns)) {
      check(false, `${where}: ${topic} publish time ${message.publishTime} for log time ${message.logTime}`);
    }
    t.count++;
    if (message.logTime < t.start) t.start = message.logTime;
    if (message.logTime > t.end) t.end = message.logTime;
    this.total++;
    this.lastLogTime = message.logTime;
  }
  // Compares with the sidecar's per-channel list.
  expect(channels, where) {
    for (const c of channels) {
      const got = this.byTopic.get(c.topic) ?? { count: 0, start: 0n, end: 0n };
      check(got.count === c.count, `${where}: ${c.topic} has ${got.count} messages, expected ${c.count}`);
      if (c.count > 0) {
        check(got.start === BigInt(c.start_time_ns), `${where}: ${c.topic} starts at ${got.start}, expected ${c.start_time_ns}`);
        check(got.end === BigInt(c.end_time_ns), `${where}: ${c.topic} ends at ${got.end}, expected ${c.end_time_ns}`);
      }
    }
    check(this.byTopic.size === channels.filter((c) => c.count > 0).length, `${where}: topics ${[...this.byTopic.keys()]}`);
  }
}

// Reads records the way the spec lays them out: opcode, uint64 length, content.
function recordAt(bytes, offset) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  return { opcode: view.getUint8(offset), length: view.getBigUint64(offset + 1, true) };
}

async function checkIndexed(bytes) {
  const where = "indexed";
  // Initialize reads the footer and magic and validates the summary CRC.
  const reader = await McapIndexedReader.Initialize({ readable: readableOf(bytes), decompressHandlers });
  check(reader.header.profile === expected.profile, `${where}: profile "${reader.header.profile}"`);
  check(reader.header.library === expected.library, `${where}: library "${reader.header.library}"`);
  check(reader.footer.summaryCrc !== 0, `${where}: the footer has a summary CRC`);
  // The data section CRC covers the magic through the last byte before Data End.
  check(reader.dataSectionCrc !== undefined, `${where}: Data End has a CRC`);
  const dataCrc = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
  check(dataCrc === reader.dataSectionCrc, `${where}: data section CRC ${dataCrc} != ${reader.dataSectionCrc}`);

  const stats = reader.statistics;
  check(stats !== undefined, `${where}: Statistics record present`);
  check(stats.messageCount === BigInt(expected.message_count), `${where}: statistics messageCount ${stats.messageCount}`);
  check(stats.schemaCount === expected.schema_count, `${where}: statistics schemaCount ${stats.schemaCount}`);
  check(stats.channelCount === expected.channel_count, `${where}: statistics channelCount ${stats.channelCount}`);
  check(stats.chunkCount === expected.chunk_count, `${where}: statistics chunkCount ${stats.chunkCount}`);
  check(stats.messageStartTime === BigInt(expected.start_time_ns), `${where}: statistics start ${stats.messageStartTime}`);
  check(stats.messageEndTime === BigInt(expected.end_time_ns), `${where}: statistics end ${stats.messageEndTime}`);
  check(reader.chunkIndexes.length === expected.chunk_count, `${where}: ${reader.chunkIndexes.length} chunk indexes`);
  check(reader.schemasById.size === expected.schema_count, `${where}: ${reader.schemasById.size} schemas`);
  check(reader.channelsById.size === expected.channel_count, `${where}: ${reader.channelsById.size} channels`);
  for (const c of expected.channels) {
    const channel = [...reader.channelsById.values()].find((ch) => ch.topic === c.topic);
    check(channel !== undefined, `${where}: channel ${c.topic} in the summary`);
    if (!channel) continue;
    const schema = reader.schemasById.get(channel.schemaId);
    check(schema?.name === c.schema && schema?.encoding === "jsonschema", `${where}: ${c.topic} schema ${schema?.name}`);
    check(channel.messageEncoding === "json", `${where}: ${c.topic} encoding ${channel.messageEncoding}`);
    JSON.parse(new TextDecoder().decode(schema.data));
    check(stats.channelMessageCounts.get(channel.id) === BigInt(c.count), `${where}: statistics count of ${c.topic}`);
  }
  // Every Summary Offset covers exactly one group of records with its opcode.
  const groups = [Opcode.SCHEMA, Opcode.CHANNEL, Opcode.STATISTICS, Opcode.CHUNK_INDEX];
  for (const opcode of groups) {
    const so = reader.summaryOffsetsByOpcode.get(opcode);
    check(so !== undefined, `${where}: summary offset for opcode ${opcode}`);
    if (!so) continue;
    let at = so.groupStart;
    while (at < so.groupStart + so.groupLength) {
      const r = recordAt(bytes, Number(at));
      check(r.opcode === opcode, `${where}: opcode ${r.opcode} in the group of ${opcode} at ${at}`);
      at += 9n + r.length;
    }
    check(at === so.groupStart + so.groupLength, `${where}: group ${opcode} ends at ${at}`);
  }
  check(reader.summaryOffsetsByOpcode.get(Opcode.SCHEMA)?.groupStart === reader.footer.summaryStart,
    `${where}: summary_start points at the first summary group`);

  // Messages through the chunk indexes and message indexes, chunk CRCs validated, in log-time order.
  const tally = new Tally();
  let previous = -1n;
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    if (message.logTime < previous) check(false, `${where}: log time ${message.logTime} after ${previous}`);
    previous = message.logTime;
    tally.add(reader.channelsById.get(message.channelId).topic, message, where);
  }
  check(tally.total === expected.message_count, `${where}: ${tally.total} messages, expected ${expected.message_count}`);
  tally.expect(expected.channels, where);
  return tally.total;
}

function checkStream(bytes) {
  const where = "stream";
  const { records, error, done } = streamRecords(bytes);
  check(error === undefined, `${where}: ${error?.message}`);
  check(done, `${where}: reached the footer and trailing magic`);
  check(records[0]?.type === "Header", `${where}: first record ${records[0]?.type}`);
  check(records.at(-1)?.type === "Footer", `${where}: last record ${records.at(-1)?.type}`);
  const types = new Map();
  for (const r of records) types.set(r.type, (types.get(r.type) ?? 0) + 1);
  const dataEnd = records.find((r) => r.type === "DataEnd");
  check(dataEnd !== undefined, `${where}: Data End present`);
  const footer = records.at(-1);
  const dataCrc = crc32(bytes.subarray(0, Number(footer.summaryStart) - 13));
  check(dataEnd?.dataSectionCrc === dataCrc, `${where}: Data End CRC ${dataEnd?.dataSectionCrc} != ${dataCrc}`);
  // Schemas and channels appear in the data section and again in the summary.
  check(types.get("Schema") === 2 * expected.schema_count, `${where}: ${types.get("Schema")} Schema records`);
  check(types.get("Channel") === 2 * expected.channel_count, `${where}: ${types.get("Channel")} Channel records`);
  check(types.get("ChunkIndex") === expected.chunk_count, `${where}: ${types.get("ChunkIndex")} Chunk Index records`);
  check(types.get("Statistics") === 1, `${where}: one Statistics record`);
  check(types.get("MessageIndex") >= expected.chunk_count, `${where}: ${types.get("MessageIndex")} Message Index records`);
  check(types.get("SummaryOffset") === 4, `${where}: ${types.get("SummaryOffset")} Summary Offset records`);
  check(!types.has("Unknown"), `${where}: no unknown records`);
  const topics = new Map();
  const tally = new Tally();
  for (const r of records) {
    if (r.type === "Channel") topics.set(r.id, r.topic);
    if (r.type === "Message") tally.add(topics.get(r.channelId), r, where);
  }
  check(tally.total === expected.message_count, `${where}: ${tally.total} messages`);
  tally.expect(expected.channels, where);
  return [...types.entries()].map(([t, n]) => `${t} ${n}`).join(", ");
}

// A file that ends early: `spec` is the sidecar's "cut" or "killed" entry.
async function checkPartial(bytes, spec, where) {
  check(bytes.byteLength === spec.size, `${where}: file has ${bytes.byteLength} bytes, expected ${spec.size}`);
  const { records, error, done } = streamRecords(bytes);
  check(!done, `${where}: the stream reader does not report a complete file`);
  const topics = new Map();
  const tally = new Tally();
  for (const r of records) {
    if (r.type === "Channel") topics.set(r.id, r.topic);
    if (r.type === "Message") tally.add(topics.get(r.channelId), r, where);
  }
  check(tally.total === spec.message_count, `${where}: ${tally.total} messages, expected ${spec.message_count}`);
  tally.expect(spec.channels, where);
  // The indexed reader needs the footer, which is missing.
  let indexedError;
  try {
    await McapIndexedReader.Initialize({ readable: readableOf(bytes), decompressHandlers });
  } catch (e) {
    indexedError = e;
  }
  check(indexedError !== undefined, `${where}: the indexed reader refuses a file without footer`);
  const chunks = records.filter((r) => r.type === "MessageIndex").length;
  return `${tally.total} messages (${chunks} message indexes), then ` +
    `${error ? `error "${error.message}"` : "end of data"}`;
}

const full = new Uint8Array(fs.readFileSync(path.join(dir, expected.file)));
const lines = [];
async function run(what, fn) {
  try {
    lines.push(`${what}: ${await fn()}`);
  } catch (e) {
    check(false, `${what} threw: ${e.message}`);
  }
}
await run(`${expected.file} (indexed reader)`, async () => `${await checkIndexed(full)} messages in ${expected.chunk_count} chunks`);
await run(`${expected.file} (stream reader)`, () => checkStream(full));
for (const [key, spec] of [["cut", expected.cut], ["killed", expected.killed]]) {
  const bytes = new Uint8Array(fs.readFileSync(path.join(dir, spec.file)));
  await run(`${spec.file} (stream reader)`, () => checkPartial(bytes, spec, key));
}
for (const line of lines) console.log(line);
console.log(`mcap_check: ${passes} passed, ${failures} failed`);
process.exit(failures === 0 ? 0 : 1);
