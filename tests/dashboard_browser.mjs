// Opens a static HTML page in Debian's chromium (playwright-core) and checks that it has images
// and that every one of them loaded (non-zero natural size), as a reader opening the file sees.
// Usage (working directory app/study_web, where playwright-core is installed):
//   node tests/dashboard_browser.mjs /path/to/index.html MIN_IMAGES
import { createRequire } from "node:module";
import { pathToFileURL } from "node:url";

const { chromium } = createRequire(process.cwd() + "/")("playwright-core");

const [file, minImages] = [process.argv[2], Number(process.argv[3] || 1)];
const browser = await chromium.launch({
  executablePath: "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update"],
});
let failed = false;
try {
  const page = await browser.newPage();
  await page.goto(pathToFileURL(file).href, { waitUntil: "load" });
  const imgs = await page.evaluate(() =>
    [...document.images].map((i) => ({ src: i.getAttribute("src"), w: i.naturalWidth })));
  const broken = imgs.filter((i) => !(i.w > 0));
  if (imgs.length < minImages || broken.length) {
    console.log(`FAIL: ${imgs.length} images (want >= ${minImages}), not loaded: ${JSON.stringify(broken)}`);
    failed = true;
  } else {
    console.log(`ok: ${imgs.length} images, every one loaded`);
  }
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
