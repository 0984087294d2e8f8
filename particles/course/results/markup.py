"""Students' Markdown as safe HTML: what a grader reads in ``particles review``'s pages.

A small Markdown of our own, so that nothing a student writes becomes markup
the page did not choose: every character of the text is escaped first
(``<script>`` shows as text), raw HTML is never passed through, links show
their text and address as text (no ``href``), images are not loaded (their
alt text and address show as text), and equations are kept, escaped, in
``<span class="math">`` (``$...$``, ``$$...$$``), the only elements a page's
MathJax typesets (:mod:`particles.course.results.review`). What it renders:
paragraphs, headings (``#``), bullet and numbered lists, block quotes,
fenced and indented code, inline code, ``**bold**`` and ``*italic*``.
"""

import html
import re

__all__ = ["markdown_html"]

_FENCE = re.compile(r"^\s*(```|~~~)")
_HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
_BULLET = re.compile(r"^\s*[-*+]\s+(.*)$")
_NUMBERED = re.compile(r"^\s*[0-9]+[.)]\s+(.*)$")
_QUOTE = re.compile(r"^\s*>\s?(.*)$")
# protected spans, in this order: inline code, display math, inline math
_SPANS = re.compile(r"(`+)(.+?)\1|\$\$(.+?)\$\$|\$([^$\n]+?)\$", re.S)
_IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]*)[^)]*\)")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]*)[^)]*\)")


def _inline(text):
    """One block's text as escaped HTML with code, math, bold and italic."""
    kept = []

    def keep(match):
        if match.group(2) is not None:
            kept.append(f"<code>{html.escape(match.group(2).strip())}</code>")
        elif match.group(3) is not None:
            kept.append(f'<span class="math">$${html.escape(match.group(3))}$$</span>')
        else:
            kept.append(f'<span class="math">${html.escape(match.group(4))}$</span>')
        return f"\x00{len(kept) - 1}\x00"

    text = _SPANS.sub(keep, text.replace("\x00", ""))
    text = _IMAGE.sub(lambda m: f"[image not shown: {m.group(1) or 'no description'} ({m.group(2)})]", text)
    text = _LINK.sub(lambda m: f"{m.group(1)} ({m.group(2)})", text)
    text = html.escape(text)
    text = re.sub(r"\*\*(\S(?:.*?\S)?)\*\*|__(\S(?:.*?\S)?)__", lambda m: f"<strong>{m.group(1) or m.group(2)}</strong>",
                  text)
    text = re.sub(r"(?<![\w*])\*(\S(?:.*?\S)?)\*(?![\w*])|(?<!\w)_(\S(?:.*?\S)?)_(?!\w)",
                  lambda m: f"<em>{m.group(1) or m.group(2)}</em>", text)
    text = re.sub("  \n", "<br>\n", text)
    return re.sub("\x00([0-9]+)\x00", lambda m: kept[int(m.group(1))], text)


def _blocks(lines):
    """Group lines into (kind, lines) blocks: code, heading, list, olist, quote, para."""
    blocks, k = [], 0
    while k < len(lines):
        line = lines[k]
        if _FENCE.match(line):
            fence, body, k = _FENCE.match(line).group(1), [], k + 1
            while k < len(lines) and not lines[k].strip().startswith(fence):
                body.append(lines[k])
                k += 1
            blocks.append(("code", body))
            k += 1
        elif not line.strip():
            k += 1
        elif _HEADING.match(line):
            blocks.append(("heading", [line]))
            k += 1
        elif line.startswith(("    ", "\t")) and (not blocks or blocks[-1][0] not in ("list", "olist")):
            body = []
            while k < len(lines) and (lines[k].startswith(("    ", "\t")) or not lines[k].strip()):
                body.append(lines[k][4:] if lines[k].startswith("    ") else lines[k].lstrip("\t"))
                k += 1
            blocks.append(("code", body))
        else:
            kind = ("list" if _BULLET.match(line) else "olist" if _NUMBERED.match(line)
                    else "quote" if _QUOTE.match(line) else "para")
            body = []
            while k < len(lines) and lines[k].strip() and not _FENCE.match(lines[k]) \
                    and not _HEADING.match(lines[k]):
                body.append(lines[k])
                k += 1
            blocks.append((kind, body))
    return blocks


def _items(body, pattern):
    items = []
    for line in body:
        match = pattern.match(line)
        if match:
            items.append(match.group(1))
        elif items:
            items[-1] += "\n" + line.strip()
        else:
            items.append(line.strip())
    return items


def markdown_html(text):
    """A student's Markdown as HTML that holds no markup of theirs.

    Parameters
    ----------
    text : str

    Returns
    -------
    str
        Block elements (``p``, ``h4``-``h6``, ``ul``, ``ol``, ``blockquote``,
        ``pre``) with escaped text; no attribute but ``class``; no link, image
        or script.

    Examples
    --------
    >>> markdown_html("**Yes**: <script>alert(1)</script> and $x_i$")
    '<p><strong>Yes</strong>: &lt;script&gt;alert(1)&lt;/script&gt; and <span class="math">$x_i$</span></p>'
    """
    out = []
    for kind, body in _blocks(str(text).replace("\r\n", "\n").split("\n")):
        if kind == "code":
            out.append(f"<pre><code>{html.escape(chr(10).join(body))}</code></pre>")
        elif kind == "heading":
            match = _HEADING.match(body[0])
            level = min(6, len(match.group(1)) + 3)
            out.append(f"<h{level}>{_inline(match.group(2))}</h{level}>")
        elif kind in ("list", "olist"):
            tag = "ul" if kind == "list" else "ol"
            items = _items(body, _BULLET if kind == "list" else _NUMBERED)
            out.append(f"<{tag}>" + "".join(f"<li>{_inline(item)}</li>" for item in items) + f"</{tag}>")
        elif kind == "quote":
            inner = "\n".join(_QUOTE.match(line).group(1) if _QUOTE.match(line) else line for line in body)
            out.append(f"<blockquote>{markdown_html(inner)}</blockquote>")
        else:
            out.append(f"<p>{_inline(chr(10).join(body))}</p>")
    return "\n".join(out)
