#!/usr/bin/python3
"""report.html shows every value from a results file or a profile as text (issue 65): raw HTML,
a profile text whose code fence would close the report's, and script URLs in Markdown links
never reach the page as markup."""
import os
import re
import sys
from html.parser import HTMLParser

SRC = os.environ.get("SIRL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(SRC, "report"))
import report  # noqa: E402

hostile = ("label <script>alert(1)</script> <img src=x onerror=alert(2)>\n\n"
           "[click](javascript:alert(3)) ![i](JaVaScRiPt:alert(4))\n\n"
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
            if k.lower().startswith("on") or re.match(r"\s*(javascript|vbscript|data):", v or "", re.I):
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
print("report_escaping: ok")
