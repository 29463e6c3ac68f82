#!/usr/bin/python3
"""report.html shows every value from a results file or a profile as text (issue 65): raw HTML,
a profile text whose code fence would close the report's, and script URLs in Markdown links
never reach the page as markup. The same for the report's first screen: the run's sentence (the
profile's name and description), the main claims' table (an environment's title, a method's
label), its colour classes, the table of contents and the figures' links."""
import os
import re
import sys
from html.parser import HTMLParser

SRC = os.environ.get("SIRL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(SRC, "report"))
import report  # noqa: E402

hostile = ("label <script>alert(1)</script> <img src=x onerror=alert(2)>\n\n"
           "[click](javascript:alert(3)) ![i](JaVaScRiPt:alert(4))\n\n"
           # entity-encoded and tab-split schemes, which a browser decodes (issue 65's probe)
           "[e](&#106;avascript:alert(12)) [t](java&#x09;script:alert(13))\n\n"
           "| method | value |\n|---|---|\n| <b onmouseover=alert(5)>x</b> | 1 |\n")


class Markup(HTMLParser):
    """The page's live markup: tags, event-handler attributes and script URLs."""
    def __init__(self):
        super().__init__()
        self.bad = []

    def handle_starttag(self, tag, attrs):
        if tag in ("script", "iframe", "object", "embed"):
            self.bad.append(tag)
        for k, v in attrs:
            # as a browser reads it: entities decoded (the parser does), spaces and controls dropped
            seen = re.sub(r"[\x00-\x20\x7f]", "", v or "")
            if k.lower().startswith("on") or re.match(r"(javascript|vbscript|data):", seen, re.I):
                self.bad.append(f"{tag} {k}={v}")


def live(page):
    m = Markup()
    m.feed(page)
    return m.bad


page = report.report_html("t <script>", hostile)
assert live(page) == [], (live(page), page)
assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page, page  # shown, as text
# The checker sees what the old converter let through (so it can fail).
import markdown  # noqa: E402
assert live(markdown.markdown(hostile, extensions=["tables"])), "the checker finds nothing"

# The profile's text in its fenced block: a fence inside it cannot close the block.
prof = 'description = """\n```\n</code></pre><script>alert(6)</script>\n```\n"""'
page = report.report_html("t", "\n".join(["# x", ""] + report.fenced(prof, "toml")))
assert live(page) == [] and "&lt;script&gt;alert(6)" in page, page

# The first screen, built from hostile file values: the profile's name and description, an
# environment's title (with a pipe, which must not split the table) and a method's label.
import figures  # noqa: E402
import hypotheses  # noqa: E402
import run_tables  # noqa: E402

run_tables.ENV["grid"] = {"title": "<script>alert(7)</script> Grid|Robot", "in_claims": 1}
figures.STYLE["vae"] = ("#000", "<img src=x onerror=alert(8)>")


def main_claim(name, protocol, verdict, diff, better):
    c = {"name": "vae", "n": 3, "diff": diff, "lo": diff, "hi": diff, "p": 0.01, "p_holm": 0.02,
         "dz": 1.0, "test": "t"}
    return {"env": "grid", "claim": f"{name} — … at N = 100", "protocol": protocol,
            "better": better, "comparisons": [c], "verdict": verdict, "deciding": c, "main": True,
            "converged": (1, 2)}


H = [main_claim("H1", None, "held", -0.05, "<"), main_claim("H2", "paper", "not held", -0.03, ">"),
     main_claim("H2", "linear", "inconclusive", 0.01, ">")]
prov = {"profile_name": "p<script>alert(9)</script>", "tasks_done": 1, "tasks_total": 2,
        "profile_text": 'description = "d <img src=y onerror=alert(10)> [x](javascript:alert(11))"'}
first = ["# x", "", report.run_sentence(prov, ["<b onmouseover=alert(12)>scale</b>"]), ""]
first += hypotheses.main_claims_lines(H)
rest = ["", "## <script>alert(13)</script> section", "", "![<b onmouseover=alert(14)>](fig4_fpe.png)",
        "", "![x](javascript:alert(15))"]
page = report.report_html("t", "\n".join(first + rest))
assert live(page) == [], (live(page), page)
for text in ("&lt;script&gt;alert(7)&lt;/script&gt;", "&lt;img src=x onerror=alert(8)&gt;",
             "alert(9)", "&lt;img src=y onerror=alert(10)&gt;", "&lt;b onmouseover=alert(12)&gt;",
             "&lt;script&gt;alert(13)&lt;/script&gt; section"):
    assert text in page, (text, page)
table = page[page.index('<table id="main-claims">'):page.index("</table>")]
assert "Grid|Robot" in table and table.count("<th>") == 1 + 2 + 1, table  # the pipe is text
for cls, word in (("v-held", "held"), ("v-not-held", "not held"), ("v-inconclusive", "inconclusive")):
    assert f'<td class="{cls}"><strong>{word}</strong>' in table, (cls, table)
nav = page[page.index('<nav id="contents">'):page.index("</nav>")]
assert "&lt;script&gt;alert(13)&lt;/script&gt; section" in nav and "<script" not in nav, nav
assert '<a href="fig4_fpe.png"><img' in page and 'href="javascript' not in page.lower(), page
print("report_escaping: ok")
