// telegrasp-view --record, stopped and killed: telegrasp-server, telegrasp-echo (the grasp
// events the DDS side published) and telegrasp-bot (both hands) on a loopback DDS domain.
// First a view records until its file holds a grasp event, then gets SIGTERM: its file is
// complete (the indexed reader takes it: footer, summary, statistics, every chunk's CRC) and its
// grasp events are ones echo saw. Then a second view records; once its file holds a grasp event
// in a complete chunk and one more chunk after it, it gets SIGKILL mid-run (last: a SIGKILL'ed
// participant can leave Fast DDS's shared-memory transport locked for the others). The file it
// leaves, read with the reference TypeScript reader (@mcap/core):
//   1. the stream reader reads every record up to the cut with valid CRCs and no error, and does
//      not report a complete file; the indexed reader refuses it (no footer);
//   2. the view's five channels with their schemas; every message is JSON; each channel's
//      sequence numbers run 0, 1, 2 ... without a gap; every /tf stamp is its log time;
//   3. nothing that was on disk before the kill is lost: the messages read just before it are
//      the file's first messages;
//   4. at least two chunks, some of them cut by time before they were full (1 MiB; a whole-scene
//      snapshot with object meshes may fill one on its own): a kill loses about a second;
//   5. at least one grasp event, each one echo saw (id, kind, object, hand); both of the bot's
//      hands and the scene's objects on /scene.
// Usage: BUILD/bin/telegrasp-test-domains node view_record_check.mjs --bin BUILD/bin --out DIR
//   (ctest: client_lib.view.record_killed; the wrapper leases the DDS domain)
import fs from "node:fs";
import path from "node:path";
import { Checks, fatal, options, start, startBot, stop, testDomain, until, sleep } from "./view_common.mjs";
import { McapIndexedReader, checkChannels, decompressHandlers, messagesOf, readableOf, streamRecords, timeNs } from "./mcap_common.mjs";

const kChunkSizeBytes = 1024 * 1024;  // the recorder's size cut (McapRecorder::Options)

const { bin, out } = options();
const domain = testDomain();
const checks = new Checks("client_lib.view.record_killed");
const file = path.join(out, "view.mcap");
console.log(`DDS domain ${domain}, recording ${file}`);

const dds = ["--domain", String(domain), "--profile", "loopback"];
const server = start(path.join(bin, "telegrasp-server"), dds, { log: path.join(out, "server.log") });
const echoEvents = new Map();  // event id -> echo's GraspEvent
const echo = start(path.join(bin, "telegrasp-echo"), [...dds, "--topics", "GraspEvent"], {
  log: path.join(out, "echo.log"),
  onLine: (line) => {
    const m = JSON.parse(line);
    echoEvents.set(m.event_id, m);
  },
});

// Starts telegrasp-view --record `mcap` (log `name`.stderr.log); resolves once it listens.
async function startView(name, mcap) {
  fs.rmSync(mcap, { force: true });
  let listening = false;
  const child = start(path.join(bin, "telegrasp-view"), [...dds, "--port", "0", "--address", "127.0.0.1", "--record", mcap], {
    log: path.join(out, `${name}.stderr.log`),
    onLine: (line) => { if (line.includes("http://127.0.0.1:")) listening = true; },
  });
  if (!(await until(() => listening || child.exitCode !== null, 20000, `${name} to listen`)))
    fatal(`${name} did not start (exit ${child.exitCode}): ${fs.readFileSync(path.join(out, `${name}.stderr.log`), "utf8")}`);
  return child;
}
// A file as it is now: its records (chunks included) up to the last complete one.
const readNow = (f) => streamRecords(new Uint8Array(fs.existsSync(f) ? fs.readFileSync(f) : []), { includeChunks: true });
const graspIn = (records) => messagesOf(records).some((m) => m.topic === "/grasp_events" && m.json?.kind === "grasp");
const chunksIn = (records) => records.filter((r) => r.type === "Chunk").length;
const sameAsEcho = (e) => {
  const x = echoEvents.get(e.event_id);
  return x !== undefined && x.kind === e.kind && x.object_name === e.object_name &&
         x.hand.client_id === e.hand.client_id && x.hand.side === e.hand.side;
};

const botId = `rec-${process.pid}`;
const bot = startBot(bin, out, domain, botId);

// A view stopped by SIGTERM closes its file.
const cleanFile = path.join(out, "view-sigterm.mcap");
const cleanView = await startView("view-sigterm", cleanFile);
if (!(await until(() => graspIn(readNow(cleanFile).records), 120000, "a grasp event in the first recording")))
  fatal(`no grasp event reached ${cleanFile}; see ${out}/*.log`);
const code = await stop(cleanView);
checks.check(code === 0, `telegrasp-view stopped by SIGTERM exits 0 (${code})`);
try {
  const cleanBytes = new Uint8Array(fs.readFileSync(cleanFile));
  const r = await McapIndexedReader.Initialize({ readable: readableOf(cleanBytes), decompressHandlers });
  let n = 0;
  const cleanEvents = [];
  for await (const m of r.readMessages({ validateCrcs: true })) {
    ++n;
    if (r.channelsById.get(m.channelId).topic === "/grasp_events") cleanEvents.push(JSON.parse(new TextDecoder().decode(m.data)));
  }
  checks.check(n > 0 && r.statistics?.messageCount === BigInt(n) && r.statistics.channelCount === 5 &&
               r.chunkIndexes.length === r.statistics.chunkCount,
    `the SIGTERM'ed view's file is complete: ${n} messages in ${r.statistics?.chunkCount} indexed chunks, every CRC valid`);
  checks.check(cleanEvents.length > 0 && cleanEvents.every(sameAsEcho),
    `its ${cleanEvents.length} grasp events are ones the server published`);
} catch (e) {
  checks.check(false, `the SIGTERM'ed view's file reads with the indexed reader (${e.message})`);
}

// A view killed mid-run.
const view = await startView("view", file);
let chunksAtGrasp = 0;
const grasped = await until(() => {
  const { records } = readNow(file);
  if (!graspIn(records)) return false;
  chunksAtGrasp = chunksIn(records);
  return true;
}, 120000, "a grasp event in a complete chunk of the file");
if (!grasped) fatal(`no grasp event reached ${file}; see ${out}/*.log`);
await until(() => chunksIn(readNow(file).records) > chunksAtGrasp, 30000, "one more chunk after the grasp");

// Kill the view mid-run, half a second into a chunk, right after a look at what is on disk.
await sleep(500);
const before = messagesOf(readNow(file).records);
view.kill("SIGKILL");
const killedAt = BigInt(Date.now()) * 1000000n;
await until(() => view.signalCode !== null || view.exitCode !== null, 10000, "telegrasp-view to die");
checks.check(view.signalCode === "SIGKILL", `telegrasp-view killed by SIGKILL while the bot grasps (bot still running: ${bot.exitCode === null})`);

// 1. Readable up to the cut.
const bytes = new Uint8Array(fs.readFileSync(file));
const { records, error, done } = streamRecords(bytes, { includeChunks: true });
checks.check(error === undefined, `stream reader: every record up to the cut (${error?.message ?? "no error"})`);
checks.check(!done, "stream reader: not a complete file (killed: no summary, no footer)");
let indexedError;
try {
  await McapIndexedReader.Initialize({ readable: readableOf(bytes), decompressHandlers });
} catch (e) {
  indexedError = e;
}
checks.check(indexedError !== undefined, `indexed reader refuses it (${indexedError?.message})`);

// 2. Channels, JSON, sequences, stamps.
checkChannels(checks, records, "channels");
const messages = messagesOf(records);
checks.check(messages.length > 0 && messages.every((m) => m.json !== undefined), `${messages.length} messages, every one JSON`);
const byTopic = new Map();
for (const m of messages) {
  if (!byTopic.has(m.topic)) byTopic.set(m.topic, []);
  byTopic.get(m.topic).push(m);
}
for (const [topic, list] of byTopic)
  checks.check(list.every((m, i) => m.sequence === i), `${topic}: ${list.length} messages numbered 0..${list.length - 1} without a gap`);
const tfs = byTopic.get("/tf") ?? [];
checks.check(tfs.length > 0 && tfs.every((m) => m.json.transforms.every((t) => timeNs(t.timestamp) === m.logTime)),
  `/tf: ${tfs.length} messages, every stamp its log time`);

// 3. Nothing on disk before the kill is lost.
const same = (a, b) => a.topic === b.topic && a.logTime === b.logTime && a.sequence === b.sequence;
checks.check(before.length > 0 && messages.length >= before.length && before.every((m, i) => same(m, messages[i])),
  `the ${before.length} messages on disk before the kill are the file's first (it has ${messages.length})`);

// 4. Time-cut chunks.
const chunks = records.filter((r) => r.type === "Chunk");
const cutByTime = chunks.filter((c) => c.uncompressedSize < BigInt(kChunkSizeBytes)).length;
checks.check(chunks.length >= 2 && cutByTime >= 1,
  `${chunks.length} chunks, ${cutByTime} cut by time before full (largest ${Math.max(...chunks.map((c) => Number(c.uncompressedSize)))} bytes uncompressed)`);
const spans = chunks.map((c) => Number(c.messageEndTime - c.messageStartTime) / 1e9);
const last = messages.at(-1).logTime;
console.log(`chunks span ${Math.min(...spans).toFixed(2)}..${Math.max(...spans).toFixed(2)} s of log time; ` +
  `the last message was logged ${(Number(killedAt - last) / 1e9).toFixed(2)} s before the kill; ${bytes.byteLength} bytes`);

// 5. Grasp events and the scene.
const events = (byTopic.get("/grasp_events") ?? []).map((m) => m.json);
checks.check(events.some((e) => e.kind === "grasp"), `${events.length} grasp events recorded, grasps among them`);
for (const e of events)
  checks.check(sameAsEcho(e), `event ${e.event_id} (${e.kind} of ${e.object_name} by ${e.hand.client_id}/${e.hand.side}) is one the server published`);
const entities = new Set((byTopic.get("/scene") ?? []).flatMap((m) => m.json.entities.map((x) => x.id)));
checks.check(entities.has(`hand/${botId}/left`) && entities.has(`hand/${botId}/right`), `/scene: both of ${botId}'s hands`);
checks.check([...entities].filter((id) => id.startsWith("object/")).length === 30, "/scene: the 30 objects of the scene");

await stop(bot);
await stop(echo);
await stop(server);
await sleep(100);
process.exit(checks.finish());
