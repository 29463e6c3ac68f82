// Drives the study page in Debian's chromium (playwright-core, no downloaded browser): practice,
// then every remaining recorded query by clicking the answer buttons. Usage: node study_browser.mjs URL
import { createRequire } from "node:module";

// playwright-core lives in app/study_web/node_modules (installed by scripts/setup.sh); the test
// runs with that directory as its working directory.
const { chromium } = createRequire(process.cwd() + "/")("playwright-core");

const url = process.argv[2];
const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: ["--no-sandbox"] });
const page = await browser.newPage();
const errors = [];
page.on("pageerror", (e) => errors.push(e.message));
await page.goto(url);
let clicks = 0;
for (let i = 0; i < 40; i++) {
  await page.waitForSelector("#buttons button, h2:has-text('Thank you')", { timeout: 20000 });
  if (await page.locator("h2:has-text('Thank you')").count()) break;
  const first = page.locator("#buttons button").first();
  if (process.env.VERBOSE) console.log(await page.locator("#text").innerText(), "|", await first.innerText());
  await first.click();
  clicks++;
  await page.waitForTimeout(100);
}
const done = await page.locator("h2:has-text('Thank you')").count();
await browser.close();
if (!done || errors.length) {
  console.error(`not finished after ${clicks} clicks; page errors: ${errors.join("; ")}`);
  process.exit(1);
}
console.log(`ok: the page ran to the end in chromium (${clicks} clicks)`);
