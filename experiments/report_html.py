"""The report's HTML: a Page of sections with a table of contents, tables and embedded PNG figures."""
import base64
import html
import io
import re

from report_data import plt


class Page:
    def __init__(self):
        self.parts = []
        self.toc = []

    def add(self, s):
        self.parts.append(s)

    def section(self, sid, title, level=2):
        if level == 2:
            self.toc.append((sid, title))
        self.add('<h%d id="%s">%s</h%d>' % (level, sid, html.escape(title), level))

    def p(self, text):
        self.add("<p>%s</p>" % text)

    def note(self, text):
        self.add('<p class="note">%s</p>' % text)

    def items(self, items):
        if items:
            self.add('<ul class="findings">' + "".join("<li>%s</li>" % i for i in items) + "</ul>")

    def figure(self, fig, caption=""):
        self.add('<figure><img src="%s" alt="%s"><figcaption>%s</figcaption></figure>'
                 % (figure_uri(fig), html.escape(alt_text(caption)), caption))

    def table(self, tid, header, rows, cls=""):
        out = ['<div class="scroll"><table id="%s" class="%s"><thead><tr>' % (tid, cls)]
        out += ["<th>%s</th>" % html.escape(h) for h in header]
        out.append("</tr></thead><tbody>")
        for r in rows:
            out.append("<tr>" + "".join("<td>%s</td>" % c for c in r) + "</tr>")
        out.append("</tbody></table></div>")
        self.add("".join(out))


def alt_text(caption_html):
    """A caption's words without its markup, for an image's alt attribute."""
    return html.unescape(re.sub(r"<[^>]+>", "", caption_html)).strip() or "plot"


def figure_uri(fig, dpi=96):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def section_plot(page, sid, title, result, caption, notes=()):
    """A plot section: the figure, or a note saying why there is none; notes follow either way."""
    page.section(sid, title)
    fig, reason = result
    if fig is None:
        page.note("Plot omitted: %s." % html.escape(reason))
    else:
        page.figure(fig, caption)
    for n in notes:
        page.note(n)


CSS = """
body{font:14px/1.45 sans-serif;margin:2em auto;max-width:1200px;color:#222;padding:0 1em}
h1{margin-bottom:0}h2{border-bottom:1px solid #ccc;margin-top:2em}
table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ddd;padding:2px 6px;text-align:right}
th{background:#f3f3f3;position:sticky;top:0}td:first-child,th:first-child{text-align:left}
.scroll{overflow:auto;max-height:600px;margin:1em 0}.note{color:#777;font-style:italic}
figure{margin:1em 0}figure img{max-width:100%}figcaption{color:#555;font-size:12px}
img.render{image-rendering:pixelated;max-width:480px}pre{background:#f7f7f7;padding:.5em;overflow:auto;max-height:300px}
ul.findings li{margin:.3em 0}.pair{display:flex;gap:1em;flex-wrap:wrap;align-items:flex-start}
.pair div{text-align:center;font-size:12px}.ci{color:#666;font-size:90%;white-space:nowrap}
.v-faster{color:#1a7f37;font-weight:bold}.v-slower{color:#b3261e;font-weight:bold}.v-none{color:#555}
.v-same{color:#555;font-style:italic}td.l{text-align:left}img.scale{max-width:480px;display:block}
"""
