// telegrasp-view's built-in page in headless Chromium (Debian's /usr/bin/chromium, WebGL through
// SwiftShader, driven by playwright-core): while a bot grasps over loopback DDS, the page at
// http://127.0.0.1:PORT/ connects, shows the scene, and once an object is held the test saves a
// screenshot (OUT/view_page.png) and checks it:
//   - the page lists both hands and every object, and the held object;
//   - around the holding hand's palm on screen there are pixels of the hand's colours (skin or
//     blocked red), and around the held object pixels of its holder's colour;
//   - the page reported no JavaScript error (window errors, page errors, console errors).
// Usage: BUILD/bin/telegrasp-test-domains node view_page_check.mjs --bin BUILD/bin --out DIR
//   (ctest: client_lib.view.browser_page; the wrapper leases the DDS domain)
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { Checks, fatal, installHint, need, options, startBot, startServerAndView, stop, testDomain, until, sleep } from "./view_common.mjs";

const kChromium = "/usr/bin/chromium";
const kRadius = 70;           // px around a projected point that are searched for a colour
const kMinPixels = 40;        // pixels of a colour that count as "present"

const playwright = await need("playwright-core");
if (!fs.existsSync(kChromium)) fatal(`${kChromium} is missing: ${installHint}`);

const { bin, out } = options();
const domain = testDomain();
const checks = new Checks("view.browser_page");
console.log(`DDS domain ${domain}, artefacts in ${out}`);

const { server, view, port } = await startServerAndView(bin, out, domain);
const clientId = `pagetest-${process.pid}`;
const bot = startBot(bin, out, domain, clientId);

const profile = fs.mkdtempSync(path.join(os.tmpdir(), "telegrasp-chromium-"));
const context = await playwright.chromium.launchPersistentContext(profile, {
  executablePath: kChromium,
  headless: true,
  viewport: { width: 1100, height: 640 },
  args: ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run"],
});
const errors = [];
let result = 1;
try {
  const page = context.pages()[0] ?? (await context.newPage());
  page.on("pageerror", (e) => errors.push(`page error: ${e.message}`));
  page.on("console", (m) => {
    if (m.type() === "error") errors.push(`console error: ${m.text()}`);
  });
  page.on("requestfailed", (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(`http://127.0.0.1:${port}/`, { waitUntil: "load" });

  const summary = () => page.evaluate(() => window.telegraspView?.summary() ?? null);
  // The scene: both hands, the objects, and then an object held by one of them.
  checks.check(await until(async () => {
    const s = await summary();
    return s && s.connected && s.hands.length === 2 && s.objects.length > 0 && s.frames > 10;
  }, 30000, "the page to show both hands and the objects"), "the page connected and shows both hands and the objects");
  // Wait for a held object, look at its hand (the camera follows it), take the screenshot, and
  // keep it if the object was still held just after; a bot holds for about a second, so retry.
  const shot = path.join(out, "view_page.png");
  let heldObject = null, hand = null, palmAt = null, objectAt = null;
  for (let attempt = 0; attempt < 30 && !hand; ++attempt) {
    let held = null;
    if (!(await until(async () => {
      held = (await summary())?.objects.find((o) => o.held) ?? null;
      return held !== null;
    }, 60000, "an object held by a hand"))) break;
    await page.evaluate((key) => window.telegraspView.select(key), held.holder);
    await sleep(200);
    // The camera follows the hand and the bot keeps moving, so the points are read just before
    // and just after the screenshot, and the pixels are looked for around both: the shot shows
    // the scene at some moment between the two.
    const points = () =>
      page.evaluate(
        ([key, id]) => [window.telegraspView.screenPoint(`${key}/palm`), window.telegraspView.screenPoint(`object/${id}`)],
        [held.holder, held.id]);
    const before = await points();
    await page.screenshot({ path: shot });
    const after = await points();
    const s = await summary();
    const still = s.objects.find((o) => o.id === held.id && o.held && o.holder === held.holder);
    if (!still) continue;
    heldObject = still;
    hand = s.hands.find((h) => h.key === still.holder);
    palmAt = before[0] && after[0] ? [before[0], after[0]] : null;
    objectAt = before[1] && after[1] ? [before[1], after[1]] : null;
  }
  checks.check(hand !== null, `screenshot ${shot} taken while ${heldObject?.name} was held by ${heldObject?.holder}`);
  checks.check(palmAt && objectAt, `the palm and the held object project onto the page (${JSON.stringify(palmAt)}, ${JSON.stringify(objectAt)})`);

  const png = fs.readFileSync(shot).toString("base64");
  const counts = await page.evaluate(async ({ png, palmAt, objectAt, handColour, radius }) => {
    const image = new Image();
    image.src = `data:image/png;base64,${png}`;
    await image.decode();
    const c = document.createElement("canvas");
    c.width = image.width;
    c.height = image.height;
    const g = c.getContext("2d");
    g.drawImage(image, 0, 0);
    const { data, width, height } = g.getImageData(0, 0, c.width, c.height);
    const hsv = (r, gr, b) => {
      const max = Math.max(r, gr, b), min = Math.min(r, gr, b), d = max - min;
      let h = 0;
      if (d > 0) h = max === r ? ((gr - b) / d) % 6 : max === gr ? (b - r) / d + 2 : (r - gr) / d + 4;
      return [(h * 60 + 360) % 360, max === 0 ? 0 : d / max, max / 255];
    };
    const hueDistance = (a, b) => Math.min(Math.abs(a - b), 360 - Math.abs(a - b));
    const [holderHue, holderSat] = hsv(...handColour.map((v) => v * 255));
    const isSkin = ([h, s, v]) => h >= 10 && h <= 40 && s >= 0.15 && s <= 0.6 && v >= 0.3;
    const isRed = ([h, s, v]) => hueDistance(h, 0) <= 12 && s >= 0.5 && v >= 0.3;
    const isHolder = ([h, s, v]) => hueDistance(h, holderHue) <= 15 && s >= 0.6 * holderSat && v >= 0.2;
    const count = (at, test) => {
      let n = 0, blank = true;
      const first = data.slice(0, 3).join();
      for (let y = Math.max(0, Math.round(at.y - radius)); y < Math.min(height, at.y + radius); ++y)
        for (let x = Math.max(0, Math.round(at.x - radius)); x < Math.min(width, at.x + radius); ++x) {
          const i = 4 * (y * width + x);
          if (test(hsv(data[i], data[i + 1], data[i + 2]))) ++n;
        }
      return n;
    };
    let distinct = new Set();
    for (let i = 0; i < data.length; i += 4 * 97) distinct.add(`${data[i] >> 3},${data[i + 1] >> 3},${data[i + 2] >> 3}`);
    return {
      handPixels: Math.max(...palmAt.map((at) => count(at, (p) => isSkin(p) || isRed(p)))),
      objectPixels: Math.max(...objectAt.map((at) => count(at, isHolder))),
      distinctColours: distinct.size,
    };
  }, { png, palmAt, objectAt, handColour: hand.colour, radius: kRadius });
  console.log(`pixels: ${JSON.stringify(counts)}`);
  checks.check(counts.distinctColours > 20, `the screenshot is not blank (${counts.distinctColours} distinct colours)`);
  checks.check(counts.handPixels >= kMinPixels, `${counts.handPixels} pixels of the hand's colours (skin, blocked red) around its palm`);
  checks.check(counts.objectPixels >= kMinPixels, `${counts.objectPixels} pixels of the holder's colour around the held object`);
  const pageErrors = await page.evaluate(() => window.telegraspView.errors);
  errors.push(...pageErrors);
  checks.check(errors.length === 0, `no JavaScript error${errors.length ? `: ${errors.join("; ")}` : ""}`);
  result = checks.finish();
} catch (error) {
  console.error(`FAIL: ${error.stack ?? error}`);
  checks.finish();
  result = 1;
} finally {
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
  await stop(bot);
  await Promise.all([stop(view), stop(server)]);
}
process.exit(result);
