# The project's own markdown links resolve: every relative link in README.md, CHANGELOG.md and
# docs/*.md names a file of the repository, and every #anchor a heading of that file (GitHub's
# slugs), so the README's results table never points at a section that was renamed.
from pathlib import Path
import re

ROOT = Path(__file__).resolve().parents[1]
LINK = re.compile(r'\[[^\]]*\]\(([^)\s]+)\)')
FENCE = re.compile(r'^```.*?^```', re.S | re.M)


def slug(heading: str) -> str:
    """Return the GitHub anchor of a heading: lower case, punctuation dropped, spaces to -."""
    text = re.sub(r'[`*]|\[([^\]]*)\]\([^)]*\)', r'\1', heading.strip()).lower()
    return re.sub(r'[^\w\- ]', '', text).replace(' ', '-')


def anchors(path: Path) -> set:
    """Return the heading slugs of a markdown file (repeats numbered) and its ``<a id>``s."""
    text = FENCE.sub('', path.read_text())
    seen, out = {}, set(re.findall(r'<a id="([^"]+)"', text))
    for line in text.splitlines():
        m = re.match(r'#{1,6} (.+)', line)
        if m:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f'{base}-{n}')
    return out


def links(path: Path):
    for target in LINK.findall(FENCE.sub('', path.read_text())):
        if not re.match(r'[a-z]+:', target):
            yield target


def broken(path: Path) -> list:
    bad = []
    for target in links(path):
        file, _, anchor = target.partition('#')
        dest = (path.parent / file).resolve() if file else path
        if not dest.exists():
            bad.append(f'{target} (no such file)')
        elif anchor and dest.suffix == '.md' and anchor not in anchors(dest):
            bad.append(f'{target} (no such heading)')
    return bad


def test_slug_follows_github():
    assert slug("Session 13: the swing baseline's own error; held-out set N (blind)") == \
        'session-13-the-swing-baselines-own-error-held-out-set-n-blind'
    assert slug('End-to-end: `gyro-char allan` on a 3 h bag') == \
        'end-to-end-gyro-char-allan-on-a-3-h-bag'


def test_a_renamed_heading_is_caught(tmp_path):
    (tmp_path / 'a.md').write_text('# Real title\n\n<a id="kept"></a>see [x](#old-title), '
                                   '[y](b.md), [z](#kept), [w](#real-title)\n')
    assert broken(tmp_path / 'a.md') == ['#old-title (no such heading)', 'b.md (no such file)']


def test_every_relative_link_in_the_docs_resolves():
    files = [ROOT / 'README.md', ROOT / 'CHANGELOG.md'] + sorted((ROOT / 'docs').glob('*.md'))
    bad = {str(f.relative_to(ROOT)): broken(f) for f in files}
    assert {k: v for k, v in bad.items() if v} == {}
    assert sum(len(list(links(f))) for f in files) > 20      # the check saw the links
