// Opens a report.html in Debian's chromium (playwright-core) and checks what a reader sees first:
// the title, one sentence on the run and the main claims' table (#main-claims), each verdict cell
// coloured by its verdict's class; a table of contents after it whose every link lands on a
// section; the table of every claim (#summary, with a verdict in every row); no Markdown table
// syntax left as text; every image loaded and a link to its own file (full size on a click).
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
  // The first screen: <h1> title, <p> the run's sentence, then the main claims' table.
  const first = await page.evaluate(() =>
    [...document.body.children].slice(0, 3).map((el) => ({ tag: el.tagName, id: el.id })),
  );
  const want = [{ tag: "H1", id: "" }, { tag: "P", id: "" }, { tag: "TABLE", id: "main-claims" }];
  if (JSON.stringify(first) !== JSON.stringify(want))
    failures.push(`the page opens with ${JSON.stringify(first)}, not the title, a sentence and #main-claims`);
  const cls = { held: "v-held", "not held": "v-not-held", inconclusive: "v-inconclusive", "not run": "v-none", "not evaluated": "v-none" };
  const main = await page.evaluate(() => {
    const t = document.getElementById("main-claims");
    if (!t) return null;
    return [...t.querySelectorAll("tbody td")].map((td) => ({
      bold: td.firstElementChild?.tagName === "STRONG" ? td.firstElementChild.innerText.trim() : null,
      cls: td.className,
      colour: getComputedStyle(td).backgroundColor,
    }));
  });
  if (!main || main.length === 0) failures.push("the main claims' table has no cells");
  else {
    const verdictCells = main.filter((c) => c.bold && c.bold in cls);
    if (verdictCells.length === 0) failures.push("no verdict cell in the main claims' table");
    for (const c of verdictCells) {
      if (c.cls !== cls[c.bold]) failures.push(`main claims: a '${c.bold}' cell has class '${c.cls}'`);
      if (c.colour === "rgba(0, 0, 0, 0)") failures.push(`main claims: a '${c.bold}' cell has no colour`);
    }
  }
  // The table of contents: after the main claims, before the first section; every link lands.
  const toc = await page.evaluate(() => {
    const nav = document.getElementById("contents");
    if (!nav) return null;
    const links = [...nav.querySelectorAll("a")].map((a) => a.getAttribute("href"));
    const h2 = [...document.querySelectorAll("h2")].map((h) => "#" + h.id);
    const main = document.getElementById("main-claims");
    return {
      links, h2,
      dangling: links.filter((l) => !l.startsWith("#") || !document.getElementById(l.slice(1))),
      afterMain: !!main && !!(main.compareDocumentPosition(nav) & Node.DOCUMENT_POSITION_FOLLOWING),
      beforeSections: h2.length === 0 || !!(nav.compareDocumentPosition(document.querySelector("h2")) & Node.DOCUMENT_POSITION_FOLLOWING),
    };
  });
  if (!toc) failures.push("no table of contents (#contents)");
  else {
    if (toc.dangling.length) failures.push(`contents links that land nowhere: ${JSON.stringify(toc.dangling)}`);
    if (JSON.stringify(toc.links) !== JSON.stringify(toc.h2)) failures.push("the contents do not list every section, in order");
    if (!toc.afterMain || !toc.beforeSections) failures.push("the contents are not between the main claims and the first section");
  }
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
    [...document.images].map((im) => ({
      src: im.getAttribute("src"),
      ok: im.complete && im.naturalWidth > 0,
      link: im.parentElement.tagName === "A" ? im.parentElement.getAttribute("href") : null,
    })),
  );
  if (images.length === 0) failures.push("the report shows no image");
  for (const im of images) {
    if (!im.ok) failures.push(`image did not load: ${im.src}`);
    if (im.link !== im.src) failures.push(`image ${im.src} does not open its file (link ${im.link})`);
  }
  const tables = await page.evaluate(() => document.querySelectorAll("table").length);
  if (failures.length === 0)
    console.log(
      `ok: report.html opens with the main claims (${main.length} cells, coloured by verdict), ` +
        `a table of contents (${toc.links.length} sections, every link lands), the summary table ` +
        `(${summary.rows.length} claims), ${tables} HTML tables, no Markdown syntax visible, ` +
        `${images.length} images loaded, each opening its file`,
    );
} finally {
  await browser.close();
}
if (failures.length) {
  console.error("FAIL: " + failures.join("; "));
  process.exit(1);
}
