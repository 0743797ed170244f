// What the telegrasp-view tests share: loading npm packages with a clear failure, a free DDS
// domain and the processes of a grasp over loopback DDS (telegrasp-server, -echo, -view, -bot),
// stopped when the test ends however it ends.
import { spawn } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

export const here = path.dirname(fileURLToPath(import.meta.url));
export const installHint = "run deploy/install-deps.sh (it installs chromium and runs npm ci in tests/js)";

export function fatal(what) {
  console.error(`FAIL: ${what}`);
  process.exit(1);
}

// Imports an npm package of tests/js, failing (never skipping) with the install hint.
export async function need(name) {
  if (!fs.existsSync(path.join(here, "node_modules"))) fatal(`${path.join(here, "node_modules")} is missing: ${installHint}`);
  try {
    return await import(name);
  } catch (error) {
    fatal(`cannot load the npm package ${name} (${error.message}): ${installHint}`);
  }
}

// Counts checks; ends with "N passed, M failed" and the exit status.
export class Checks {
  constructor(name) {
    this.name = name;
    this.passed = 0;
    this.failed = 0;
  }
  check(ok, what) {
    if (ok) {
      ++this.passed;
      console.log(`ok: ${what}`);
    } else {
      ++this.failed;
      console.error(`FAIL: ${what}`);
    }
    return ok;
  }
  finish() {
    console.log(`${this.name}: ${this.passed} passed, ${this.failed} failed`);
    return this.failed === 0 && this.passed > 0 ? 0 : 1;
  }
}

// The DDS domain telegrasp-test-domains leased for this test (TELEGRASP_TEST_DOMAIN), so that
// concurrent test runs never meet: run the script under it (ctest does).
export function testDomain() {
  const domain = process.env.TELEGRASP_TEST_DOMAIN;
  if (!/^[0-9]+$/.test(domain ?? "")) {
    console.error("no DDS domain: run this under telegrasp-test-domains (build/bin), which leases one");
    process.exit(2);
  }
  return Number(domain);
}

const children = new Set();
function stopAll() {
  for (const child of children) if (child.exitCode === null) child.kill("SIGTERM");
}
process.on("exit", stopAll);
for (const signal of ["SIGINT", "SIGTERM"]) process.on(signal, () => process.exit(130));

// Starts `program` with `args`; its stderr (and stdout unless onLine takes it) goes to `log`.
export function start(program, args, { log, onLine } = {}) {
  const child = spawn(program, args, { stdio: ["ignore", "pipe", "pipe"] });
  children.add(child);
  const logStream = log ? fs.createWriteStream(log) : null;
  child.stderr.on("data", (d) => logStream?.write(d));
  let pending = "";
  child.stdout.on("data", (d) => {
    if (!onLine) return logStream?.write(d);
    pending += d.toString();
    let nl;
    while ((nl = pending.indexOf("\n")) >= 0) {
      onLine(pending.slice(0, nl));
      pending = pending.slice(nl + 1);
    }
  });
  child.on("exit", () => children.delete(child));
  return child;
}

export function stop(child, timeoutMs = 5000) {
  return new Promise((resolve) => {
    if (child.exitCode !== null || child.signalCode !== null) return resolve(child.exitCode);
    const timer = setTimeout(() => child.kill("SIGKILL"), timeoutMs);
    child.on("exit", (code) => {
      clearTimeout(timer);
      resolve(code);
    });
    child.kill("SIGTERM");
  });
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

export async function until(condition, timeoutMs, what) {
  const deadline = Date.now() + timeoutMs;
  while (Date.now() < deadline) {
    if (await condition()) return true;
    await sleep(100);
  }
  console.error(`timed out after ${timeoutMs / 1000} s waiting for ${what}`);
  return false;
}

// Parses the options every view test takes: --bin DIR (the build's bin/), --out DIR (artefacts).
export function options() {
  const args = process.argv.slice(2);
  const get = (flag) => {
    const i = args.indexOf(flag);
    return i >= 0 ? args[i + 1] : undefined;
  };
  const bin = get("--bin");
  const out = get("--out");
  if (!bin || !out) fatal(`usage: node ${path.basename(process.argv[1])} --bin BUILD/bin --out DIR`);
  for (const tool of ["telegrasp-server", "telegrasp-view", "telegrasp-bot", "telegrasp-echo"])
    if (!fs.existsSync(path.join(bin, tool))) fatal(`${path.join(bin, tool)} is missing: build it first`);
  fs.mkdirSync(out, { recursive: true });
  return { bin, out };
}

// Starts telegrasp-server and telegrasp-view (any free port, 127.0.0.1) on their own domain;
// resolves { domain, port, server, view } once the view listens. $TELEGRASP_VIEW_TEST_OBJECTS
// names a mesh folder for the server (e.g. ../shared/data/ycb for the README's screenshot).
export async function startServerAndView(bin, out, domain) {
  const objects = process.env.TELEGRASP_VIEW_TEST_OBJECTS ? ["--objects", process.env.TELEGRASP_VIEW_TEST_OBJECTS] : [];
  const server = start(path.join(bin, "telegrasp-server"), ["--domain", String(domain), "--profile", "loopback", ...objects], {
    log: path.join(out, "server.log"),
  });
  let port = null;
  const viewLog = fs.createWriteStream(path.join(out, "view.log"));
  const view = start(path.join(bin, "telegrasp-view"), ["--domain", String(domain), "--profile", "loopback",
    "--port", "0", "--address", "127.0.0.1"], {
    log: path.join(out, "view.stderr.log"),
    onLine: (line) => {
      viewLog.write(line + "\n");
      const m = line.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (m) port = Number(m[1]);
    },
  });
  const ok = await until(() => port !== null || view.exitCode !== null, 20000, "telegrasp-view to listen");
  if (!ok || port === null)
    fatal(`telegrasp-view did not start (exit ${view.exitCode}): ${fs.readFileSync(path.join(out, "view.stderr.log"), "utf8")}`);
  return { server, view, port };
}

export function startBot(bin, out, domain, clientId) {
  return start(path.join(bin, "telegrasp-bot"), ["--domain", String(domain), "--profile", "loopback",
    // Five rounds: a loaded machine's screenshots can outlast several one-second holds; the checks
    // stop the bot when they are done.
    "--client-id", clientId, "--hands", "both", "--skill", "perfect", "--trials", "5", "--timeout-s", "60"], {
    log: path.join(out, "bot.log"),
  });
}
