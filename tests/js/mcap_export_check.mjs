// Reads the MCAP file `telegrasp-replay session.tgrec --export-mcap session.mcap` wrote with the
// reference TypeScript reader (@mcap/core) and checks it against DIR/expected.json, which
// telegrasp-replay-mcap-sample (tests/server/replay_mcap_sample.cc) read from the recording
// itself, independently of the export:
//   1. every record validates: the indexed reader (footer, magic, summary CRC, statistics, chunk
//      indexes, each chunk's CRC) and the stream reader (every record in file order to the
//      footer), the data section CRC recomputed here; every message is JSON;
//   2. the view's five channels with their schemas;
//   3. counts per channel against the recording's outputs: one /grasp_events message per
//      GraspEvent (same ids, kinds and objects, logged within one view update of the event's
//      server time), one /server_status per ServerStatus (same ticks), /grasp_state at most one
//      per GraspState, /tf at most one per tick; every object and hand on /scene, the removed
//      hand deleted;
//   4. the time range: the recording's start plus the server time of its first and last output,
//      in the statistics and in the messages; every /tf stamp equals its message's log time;
//   5. every palm pose on /tf is the newest pose the recording holds for that hand up to the
//      message's log time (within 1e-6: /tf rounds to 1e-7).
// Usage: node tests/js/mcap_export_check.mjs DIR   (ctest: tools.replay_mcap.reference_reader)
import fs from "node:fs";
import path from "node:path";
import { Checks, fatal } from "./view_common.mjs";
import {
  McapIndexedReader, checkChannels, crc32, decoded, decompressHandlers, fromTransform, messagesOf, readableOf,
  samePose, streamRecords, timeNs,
} from "./mcap_common.mjs";

const kPoseTolerance = 1e-6;

const dir = process.argv[2];
if (!dir) fatal("usage: node mcap_export_check.mjs DIR");
const expected = JSON.parse(fs.readFileSync(path.join(dir, "expected.json"), "utf8"));
const bytes = new Uint8Array(fs.readFileSync(path.join(dir, expected.file)));
const checks = new Checks("tools.replay_mcap.reference_reader");

// 1. Indexed: footer, summary and chunk CRCs; messages in log-time order through the indexes.
const reader = await McapIndexedReader.Initialize({ readable: readableOf(bytes), decompressHandlers });
checks.check(reader.dataSectionCrc === crc32(bytes.subarray(0, Number(reader.dataEndOffset))), "indexed: data section CRC");
checks.check(reader.footer.summaryCrc !== 0, "indexed: the footer has a summary CRC");
const indexed = [];
for await (const m of reader.readMessages({ validateCrcs: true })) indexed.push(decoded(reader.channelsById.get(m.channelId).topic, m));
const stats = reader.statistics;
checks.check(stats !== undefined && stats.messageCount === BigInt(indexed.length),
  `indexed: ${indexed.length} messages, statistics say ${stats?.messageCount}`);
checks.check(stats.chunkCount === reader.chunkIndexes.length && stats.chunkCount > 0, `indexed: ${stats.chunkCount} chunks, all indexed`);

// Stream: every record in file order, to the footer and trailing magic.
const stream = streamRecords(bytes);
checks.check(stream.error === undefined && stream.done, `stream: read to the end (${stream.error?.message ?? "no error"})`);
checks.check(stream.records[0]?.type === "Header" && stream.records.at(-1)?.type === "Footer", "stream: Header first, Footer last");
const streamed = messagesOf(stream.records);
checks.check(streamed.length === indexed.length, `stream: ${streamed.length} messages, as indexed`);
checks.check(streamed.every((m) => m.json !== undefined), "every message is JSON");

// 2. Channels.
checkChannels(checks, stream.records, "channels");

// 3. Counts per channel, against the recording.
const byTopic = (topic) => indexed.filter((m) => m.topic === topic);
const events = byTopic("/grasp_events");
const period = 1e9 / expected.rate_hz;
checks.check(events.length === expected.outputs.grasp_event && events.length > 0,
  `/grasp_events: ${events.length} messages, ${expected.outputs.grasp_event} GraspEvents recorded`);
events.forEach((m, i) => {
  const e = expected.events[i];
  const late = Number(m.logTime - BigInt(e?.time_ns ?? "0"));
  checks.check(e !== undefined && m.json.event_id === e.event_id && m.json.kind === e.kind && m.json.object_name === e.object_name &&
               late >= 0 && late <= period + 1e6,
    `/grasp_events ${i}: event ${m.json.event_id} ${m.json.kind} of ${m.json.object_name}, logged ${(late / 1e6).toFixed(1)} ms after its server time`);
});
const statuses = byTopic("/server_status");
checks.check(statuses.length === expected.outputs.server_status &&
             statuses.every((m, i) => m.json.tick === expected.status_ticks[i]),
  `/server_status: ${statuses.length} messages (ticks ${statuses.map((m) => m.json.tick)}), ${expected.outputs.server_status} recorded`);
const states = byTopic("/grasp_state");
checks.check(states.length >= 1 && states.length <= expected.outputs.grasp_state &&
             states.every((m) => expected.hands.includes(`${m.json.hand.client_id}/${m.json.hand.side}`)),
  `/grasp_state: ${states.length} messages, at most the ${expected.outputs.grasp_state} GraspStates recorded, of known hands`);
const tfs = byTopic("/tf");
// A SceneState goes out every tick; the export adds the closing keyframe.
checks.check(tfs.length >= 1 && tfs.length <= expected.outputs.scene_state + 1,
  `/tf: ${tfs.length} messages, at most one per tick (${expected.outputs.scene_state}) and the closing keyframe`);
const scenes = byTopic("/scene");
const firstScene = new Set(scenes[0]?.json.entities.map((e) => e.id));
checks.check(expected.objects.every((o) => firstScene.has(o)), `/scene: the first update has every object (${expected.objects})`);
const deleted = new Set(scenes.flatMap((m) => m.json.deletions.map((d) => d.id)));
const entities = new Set(scenes.flatMap((m) => m.json.entities.map((e) => e.id)));
for (const hand of expected.hands) {
  checks.check(entities.has(`hand/${hand}`), `/scene: hand/${hand} drawn`);
  if (expected.outputs.hand_removed >= expected.hands.length) checks.check(deleted.has(`hand/${hand}`), `/scene: hand/${hand} deleted once removed`);
}

// 4. Time range.
const start = BigInt(expected.start_time_ns), end = BigInt(expected.end_time_ns);
checks.check(stats.messageStartTime === start && stats.messageEndTime === end,
  `time range ${stats.messageStartTime}..${stats.messageEndTime} ns is the recording's ${start}..${end} ` +
  `(${Number(end - start) / 1e9} s from ${new Date(Number(start / 1000000n)).toISOString()})`);
checks.check(indexed[0].logTime === start && indexed.at(-1).logTime === end && indexed.every((m) => m.publishTime === m.logTime),
  "the first and last message at the range's ends; publish time = log time");
checks.check(tfs.every((m) => m.json.transforms.every((t) => timeNs(t.timestamp) === m.logTime)), "every /tf stamp is its log time");

// 5. Palm poses against the recording.
const palms = new Map();  // frame -> recorded palms in record order
for (const p of expected.palms) {
  if (!palms.has(p.frame)) palms.set(p.frame, []);
  palms.get(p.frame).push({ time: BigInt(p.time_ns), pose: { p: p.p, q: p.q } });
}
let compared = 0, wrong = 0;
for (const m of tfs) {
  for (const t of m.json.transforms) {
    const recorded = palms.get(t.child_frame_id);
    if (!recorded) continue;
    const upTo = recorded.filter((p) => p.time <= m.logTime);
    ++compared;
    if (upTo.length === 0 || !samePose(fromTransform(t), upTo.at(-1).pose, kPoseTolerance)) {
      if (++wrong <= 3) console.error(`  ${t.child_frame_id} at ${m.logTime}: ${JSON.stringify(fromTransform(t))}`);
    }
  }
}
checks.check(compared > 0 && wrong === 0, `/tf: ${compared} palm poses, each the newest recorded up to its log time (${wrong} not)`);

console.log(`${expected.file}: ${indexed.length} messages in ${stats.chunkCount} chunks, ${bytes.byteLength} bytes; ` +
  [...new Set(indexed.map((m) => m.topic))].map((t) => `${t} ${byTopic(t).length}`).join(", "));
process.exit(checks.finish());
