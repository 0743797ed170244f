// What the checks of telegrasp-view's MCAP files share (mcap_export_check.mjs for
// telegrasp-replay --export-mcap, view_record_check.mjs for telegrasp-view --record): the
// reference TypeScript reader @mcap/core with zstd (fzstd), the file read record by record, and
// the channels telegrasp-view writes.
import { need } from "./view_common.mjs";

const core = await need("@mcap/core");
const { decompress: decompressZstd } = await need("fzstd");
const { crc32 } = await need("@foxglove/crc");
export const { McapIndexedReader, McapStreamReader, Opcode } = core;
export { crc32 };

export const decompressHandlers = {
  zstd: (buffer, size) => {
    const out = decompressZstd(buffer, new Uint8Array(Number(size)));
    if (out.byteLength !== Number(size)) throw new Error(`zstd chunk decompressed to ${out.byteLength} bytes, header says ${size}`);
    return out;
  },
};

// The view's channels: topic -> schema name (client_lib/tools/view/channels.cc).
export const kViewChannels = new Map([
  ["/scene", "foxglove.SceneUpdate"],
  ["/tf", "foxglove.FrameTransforms"],
  ["/grasp_state", "telegrasp.GraspState"],
  ["/grasp_events", "telegrasp.GraspEvent"],
  ["/server_status", "telegrasp.ServerStatus"],
]);

export function readableOf(bytes) {
  return {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, length) => {
      if (offset + length > BigInt(bytes.byteLength)) throw new Error(`read past the end at ${offset}+${length}`);
      return bytes.subarray(Number(offset), Number(offset + length));
    },
  };
}

// Feeds `bytes` to the stream reader (CRCs validated) 64 KiB at a time, as a file that grows;
// returns every record it gave (Chunk records too with includeChunks, each before its content),
// the error that stopped it if any, and whether it saw the end.
export function streamRecords(bytes, { includeChunks = false } = {}) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true, includeChunks });
  const records = [];
  let error;
  try {
    for (let at = 0; at < bytes.byteLength; at += 65536) {
      reader.append(bytes.subarray(at, Math.min(at + 65536, bytes.byteLength)));
      for (let record; (record = reader.nextRecord()); ) records.push(record);
    }
  } catch (e) {
    error = e;
  }
  return { records, error, done: reader.done() };
}

// The messages of a record list, decoded: [{topic, logTime, publishTime, sequence, json}].
export function messagesOf(records) {
  const topics = new Map();
  const out = [];
  for (const r of records) {
    if (r.type === "Channel") topics.set(r.id, r.topic);
    if (r.type === "Message") out.push(decoded(topics.get(r.channelId), r));
  }
  return out;
}

export function decoded(topic, message) {
  let json;
  try {
    json = JSON.parse(new TextDecoder().decode(message.data));
  } catch {
    json = undefined;
  }
  return { topic, logTime: message.logTime, publishTime: message.publishTime, sequence: message.sequence, json };
}

// Checks the Schema and Channel records against the view's channels: every topic once, its
// schema by name, JSON Schema text that parses, JSON messages.
export function checkChannels(checks, records, where) {
  const schemas = new Map(records.filter((r) => r.type === "Schema").map((s) => [s.id, s]));
  const channels = records.filter((r) => r.type === "Channel");
  const seen = new Set();
  for (const c of channels) {
    if (seen.has(c.topic)) continue;  // the summary repeats them
    seen.add(c.topic);
    const schema = schemas.get(c.schemaId);
    let parsed;
    try {
      parsed = JSON.parse(new TextDecoder().decode(schema?.data ?? new Uint8Array()));
    } catch {
      parsed = undefined;
    }
    checks.check(kViewChannels.get(c.topic) === schema?.name && schema?.encoding === "jsonschema" && c.messageEncoding === "json" &&
                 parsed?.type === "object" && parsed?.properties !== undefined,
      `${where}: ${c.topic} has schema ${schema?.name} (${schema?.encoding}, JSON Schema with properties), ${c.messageEncoding} messages`);
  }
  checks.check([...kViewChannels.keys()].every((t) => seen.has(t)) && seen.size === kViewChannels.size,
    `${where}: the view's five channels (${[...seen].join(", ")})`);
}

// A foxglove Time {sec, nsec} in ns.
export const timeNs = (t) => BigInt(t.sec) * 1000000000n + BigInt(t.nsec);

// Pose comparison: p in m, q as [w, x, y, z] (q and -q are the same rotation).
export function samePose(a, b, tolerance) {
  const dp = Math.hypot(a.p[0] - b.p[0], a.p[1] - b.p[1], a.p[2] - b.p[2]);
  const dq = (s) => Math.max(...a.q.map((v, i) => Math.abs(v - s * b.q[i])));
  return dp <= tolerance && Math.min(dq(1), dq(-1)) <= tolerance;
}
export const fromTransform = (t) => ({
  p: [t.translation.x, t.translation.y, t.translation.z],
  q: [t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z],
});
