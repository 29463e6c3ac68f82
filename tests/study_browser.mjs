// Drives the study page in Debian's chromium (playwright-core, no downloaded browser): practice,
// then every remaining recorded query. Usage: node study_browser.mjs URL [arm|path]
// With "arm" (a JacoRobot study) it also checks the 3-D page's controls on the first three-panel
// screen: every panel draws the arm (7 links); the Top view button and a drag on one panel move
// the one shared camera, so every panel's picture changes; Replay all (key r) moves the arms;
// answers are given by keyboard (keys 1/2/3, Enter) as well as clicks, and the progress bar
// counts each recorded answer.
import { createRequire } from "node:module";

// playwright-core lives in app/study_web/node_modules (installed by scripts/setup.sh); the test
// runs with that directory as its working directory.
const { chromium } = createRequire(process.cwd() + "/")("playwright-core");

const url = process.argv[2], arm = process.argv[3] === "arm", path = process.argv[3] === "path";
const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: ["--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader"] });
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });  // a laptop screen
const errors = [];
page.on("pageerror", (e) => errors.push(e.message));
await page.goto(url);
const fail = async (msg) => { console.error(msg); await browser.close(); process.exit(1); };
const snap = () => page.$$eval("#views canvas", (cs) => cs.map((c) => c.toDataURL()));
const allChanged = (a, b) => a.length === b.length && a.every((x, i) => x !== b[i]);

async function checkArmControls() {
  await page.waitForTimeout(400);
  const panels = await page.evaluate(() => window.__study.panels());
  if (panels.length !== 3 || panels.some((p) => p.links !== 7))
    await fail(`expected 3 panels with 7 arm links each, got ${JSON.stringify(panels)}`);
  if (!(await page.locator("#viewbar").isVisible())) await fail("the camera bar is hidden");
  const before = await snap();
  await page.click("#view-top");
  await page.waitForTimeout(300);
  const top = await snap();
  const cam = await page.evaluate(() => window.__study.camera());
  if (!allChanged(before, top) || !(cam[2] > 2)) await fail(`Top view: camera ${cam}, panels changed: ${before.map((x, i) => x !== top[i])}`);
  // Orbit one panel: the shared camera turns every panel.
  const box = await page.locator("#views canvas").first().boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 80, box.y + box.height / 2 + 30, { steps: 6 });
  await page.mouse.up();
  await page.waitForTimeout(300);
  const dragged = await snap();
  if (!allChanged(top, dragged)) await fail(`a drag on panel 1 did not move every panel: ${top.map((x, i) => x !== dragged[i])}`);
  await page.keyboard.press("s");  // side view by key
  await page.waitForTimeout(300);
  const side = await snap();
  if (!allChanged(dragged, side) || (await page.evaluate(() => window.__study.view())) !== "side")
    await fail("key s did not switch every panel to the side view");
  await page.keyboard.press("r");  // replay all: the arms move
  await page.waitForTimeout(1500);
  const moving = await snap();
  if (!allChanged(side, moving)) await fail("Replay all (key r) did not move every panel's arm");
  console.log("ok: 3 panels draw the arm; Top, a drag and key s move the shared camera of all; r replays all");
}

// With "path" (a Driver study): each of the three panels draws its trajectory (its pixels differ
// from a blank canvas's and from the other panels'), with no camera bar.
async function checkPaths() {
  const drawn = await page.$$eval("#views canvas", (cs) => {
    const blank = document.createElement("canvas");
    blank.width = cs[0].width; blank.height = cs[0].height;
    return cs.map((c) => c.toDataURL() !== blank.toDataURL());
  });
  const shots = await snap();
  if (drawn.length !== 3 || drawn.some((d) => !d)) await fail(`path panels drawn: ${drawn}`);
  if (new Set(shots).size !== 3) await fail("two path panels show the same picture");
  if (await page.locator("#viewbar").isVisible()) await fail("a camera bar on a path view");
  console.log("ok: 3 panels each draw a road path, no camera bar");
}

let answered = 0, checked = false, byKey = 0;
for (let i = 0; i < 60; i++) {
  await page.waitForSelector("#buttons button, h2:has-text('Thank you')", { timeout: 20000 });
  if (await page.locator("h2:has-text('Thank you')").count()) break;
  const first = page.locator("#buttons button").first();
  const key = await first.getAttribute("data-key");
  const recorded = (await page.locator("#text").innerText()).startsWith("Question");
  if ((arm || path) && !checked && (await page.locator("#views canvas").count()) === 3) {
    await (arm ? checkArmControls() : checkPaths());
    checked = true;
  }
  const bar = await page.locator("#bar").evaluate((b) => b.value);
  if (process.env.VERBOSE) console.log(await page.locator("#text").innerText(), "|", await first.innerText());
  if (arm && (answered % 2 === 0)) {  // every other answer by keyboard
    await page.keyboard.press(key);
    byKey++;
  } else {
    await first.click();
  }
  answered++;
  await page.waitForTimeout(150);
  if (recorded) {
    await page.waitForFunction((v) => document.getElementById("bar").value === v + 1, bar, { timeout: 5000 })
      .catch(async () => fail(`the progress bar did not count a recorded answer (was ${bar})`));
  }
}
const done = await page.locator("h2:has-text('Thank you')").count();
await browser.close();
if (!done || errors.length || ((arm || path) && !checked)) {
  console.error(`not finished after ${answered} answers (checked: ${checked}); page errors: ${errors.join("; ")}`);
  process.exit(1);
}
console.log(`ok: the page ran to the end in chromium (${answered} answers, ${byKey} by keyboard)`);
