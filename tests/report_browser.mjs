// Opens a report.html in Debian's chromium (playwright-core) and checks what a reader sees first:
// the page's first element is the summary table of claims (with a verdict in every row), no
// Markdown table syntax is left as text, and every image loaded (non-zero natural size).
// Usage (working directory app/study_web, where playwright-core is installed):
//   node tests/report_browser.mjs /path/to/report.html
import { createRequire } from "node:module";
import { pathToFileURL } from "node:url";

const { chromium } = createRequire(process.cwd() + "/")("playwright-core");

const file = process.argv[2];
const browser = await chromium.launch({
  executablePath: "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update"],
});
const failures = [];
try {
  const page = await browser.newPage();
  await page.goto(pathToFileURL(file).href, { waitUntil: "load" });
  const first = await page.evaluate(() => {
    const el = document.body.firstElementChild;
    return el ? { tag: el.tagName, id: el.id, caption: el.caption ? el.caption.innerText : "" } : null;
  });
  if (!first || first.tag !== "TABLE" || first.id !== "summary")
    failures.push(`the first element is ${JSON.stringify(first)}, not the summary table`);
  const summary = await page.evaluate(() => {
    const t = document.getElementById("summary");
    if (!t) return null;
    const head = [...t.querySelectorAll("thead th")].map((th) => th.innerText.trim());
    const col = head.indexOf("verdict");
    const rows = [...t.querySelectorAll("tbody tr")].map((tr) => tr.children[col]?.innerText.trim());
    return { head, rows };
  });
  const verdicts = new Set(["held", "not held", "inconclusive", "not evaluated (no data)", "not run"]);
  if (!summary || summary.rows.length === 0) failures.push("the summary table has no rows");
  else {
    for (const want of ["claim", "environment", "verdict", "Holm p", "power"])
      if (!summary.head.some((h) => h.startsWith(want))) failures.push(`summary lacks a '${want}' column`);
    const odd = summary.rows.filter((v) => !verdicts.has(v));
    if (odd.length) failures.push(`summary rows without a verdict word: ${JSON.stringify(odd)}`);
  }
  const text = await page.evaluate(() => document.body.innerText);
  if (text.includes("|---") || /\|\s*---/.test(text)) failures.push("literal Markdown table syntax is visible");
  const images = await page.evaluate(() =>
    [...document.images].map((im) => ({ src: im.getAttribute("src"), ok: im.complete && im.naturalWidth > 0 })),
  );
  if (images.length === 0) failures.push("the report shows no image");
  for (const im of images) if (!im.ok) failures.push(`image did not load: ${im.src}`);
  const tables = await page.evaluate(() => document.querySelectorAll("table").length);
  if (failures.length === 0)
    console.log(
      `ok: report.html opens with the summary table (${summary.rows.length} claims), ` +
        `${tables} HTML tables, no Markdown syntax visible, ${images.length} images loaded`,
    );
} finally {
  await browser.close();
}
if (failures.length) {
  console.error("FAIL: " + failures.join("; "));
  process.exit(1);
}
