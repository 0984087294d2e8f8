"""Students' Markdown as safe HTML: the usual blocks rendered, nothing of theirs left as markup."""

import re

import pytest

from particles.course.results.markup import markdown_html


@pytest.mark.parametrize("text, expected", [
    ("**bold** and *it* and _it_", "<p><strong>bold</strong> and <em>it</em> and <em>it</em></p>"),
    ("# Title", "<h4>Title</h4>"),
    ("* a\n* b `x<y`", "<ul><li>a</li><li>b <code>x&lt;y</code></li></ul>"),
    ("1. one\n2. two", "<ol><li>one</li><li>two</li></ol>"),
    ("```\nif a < b: pass\n```", "<pre><code>if a &lt; b: pass</code></pre>"),
    ("> quoted", "<blockquote><p>quoted</p></blockquote>"),
    ("$h_s^2 * w_i$ stays", '<p><span class="math">$h_s^2 * w_i$</span> stays</p>'),
    ("$$a_1 * b_2$$", '<p><span class="math">$$a_1 * b_2$$</span></p>'),
    ("snake_case_name", "<p>snake_case_name</p>"),
])
def test_the_usual_markdown_renders(text, expected):
    """Emphasis, headings, lists, code, quotes render; equations and snake_case stay as written."""
    assert markdown_html(text) == expected


@pytest.mark.parametrize("text", [
    "<script>alert(1)</script>", "<img src=x onerror=alert(1)>", '<a href="http://evil.example">x</a>',
    "![x](http://evil.example/a.png)", "[x](javascript:alert(1))", "<style>body{display:none}</style>",
    "`<b>` **<i>x</i>**", "\x00<script>\x00", "<svg onload=alert(1)>",
])
def test_nothing_a_student_writes_becomes_markup(text):
    """Raw HTML is escaped, links and images become text: only the renderer's own tags, with no attributes."""
    rendered = markdown_html(text)
    tags = re.findall(r"<\s*([a-zA-Z0-9]+)([^>]*)>", rendered)
    assert {tag for tag, _ in tags} <= {"p", "code", "strong", "em", "span"}
    assert all(attrs in ("", ' class="math"') for _, attrs in tags)
    assert "<script" not in rendered and "<a " not in rendered and "<img" not in rendered
