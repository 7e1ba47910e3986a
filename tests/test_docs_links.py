"""Every path and link the docs cite resolves, and `docs/bench/` holds only what its index lists.

Checks README.md, docs/*.md and docs/bench/INDEX.md:
- every markdown link `[text](target)` that is not a URL names a file or folder that exists, and its
  `#anchor`, where it has one, is a heading of the target (GitHub's slugs);
- every `docs/...` path written in the text (in code spans or not) exists; a `*` in it must match
  at least one file; a path written as `<commit>:docs/...` (a `git show` argument) exists in that
  commit, checked where the clone has the commit;
- every file under docs/bench/ is linked from docs/bench/INDEX.md.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md"), ROOT / "docs" / "bench" / "INDEX.md"])
LINK = re.compile(r"\]\(([^)\s]+)\)")
PATH = re.compile(r"(?:\b([0-9a-f]{7,40}):)?(?<![\w/.-])(docs/[A-Za-z0-9_.*+/-]*)")
FENCE = re.compile(r"^(```|~~~)")


def _text(doc: Path) -> str:
    """The doc without its fenced code blocks (command listings hold example output paths)."""
    lines, fenced = [], False
    for line in doc.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line.strip()):
            fenced = not fenced
            continue
        if not fenced:
            lines.append(line)
    return "\n".join(lines)


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = heading.replace("`", "").replace("*", "")
    text = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return text.replace(" ", "-")


def _anchors(doc: Path) -> set[str]:
    anchors: set[str] = set()
    counts: dict[str, int] = {}
    fenced = False
    for line in doc.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line.strip()):
            fenced = not fenced
            continue
        match = None if fenced else re.match(r"#{1,6}\s+(.*)", line)
        if match:
            slug = _slug(match.group(1))
            n = counts.get(slug, 0)
            counts[slug] = n + 1
            anchors.add(slug if n == 0 else f"{slug}-{n}")
    return anchors


def _cited(doc: Path) -> list[tuple[str, str]]:
    """(commit or "", path) for every docs/... path the doc's text names."""
    found = []
    for commit, path in PATH.findall(_text(doc)):
        path = path.rstrip(".,:;")
        if path in ("docs", "docs/"):
            continue
        found.append((commit, path))
    return found


def _git_has(commit: str, path: str) -> bool | None:
    """Whether `commit:path` exists; None where git or the commit is not available."""
    if shutil.which("git") is None:
        return None
    ok = subprocess.run(["git", "cat-file", "-e", f"{commit}^{{commit}}"], cwd=ROOT, capture_output=True)
    if ok.returncode != 0:
        return None
    spec = f"{commit}:{path.rstrip('/')}"
    return subprocess.run(["git", "cat-file", "-e", spec], cwd=ROOT, capture_output=True).returncode == 0


@pytest.mark.parametrize("doc", DOCS, ids=lambda d: str(d.relative_to(ROOT)))
def test_markdown_links_resolve(doc):
    broken = []
    for target in LINK.findall(_text(doc)):
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        resolved = doc if not path else (doc.parent / path).resolve()
        if not resolved.exists():
            broken.append(f"{target}: no such file")
        elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
            broken.append(f"{target}: no heading with anchor #{anchor}")
    assert not broken, f"{doc.relative_to(ROOT)} links to what is not there:\n" + "\n".join(broken)


@pytest.mark.parametrize("doc", DOCS, ids=lambda d: str(d.relative_to(ROOT)))
def test_cited_paths_exist(doc):
    missing = []
    for commit, path in _cited(doc):
        if commit:
            continue
        if "*" in path:
            if not list(ROOT.glob(path)):
                missing.append(f"{path}: matches nothing")
        elif not (ROOT / path).exists():
            missing.append(path)
    assert not missing, f"{doc.relative_to(ROOT)} cites paths that do not exist:\n" + "\n".join(missing)


def test_paths_cited_at_a_commit_exist_there():
    cited = [(doc, c, p) for doc in DOCS for c, p in _cited(doc) if c]
    assert cited, "the logs cite the pruned measurement files at the commit before the pruning"
    answers = [(doc, c, p, _git_has(c, p)) for doc, c, p in cited]
    if all(a is None for *_, a in answers):
        pytest.skip("git or the cited commit is not available here (a shallow clone)")
    missing = [f"{d.relative_to(ROOT)}: {c}:{p}" for d, c, p, a in answers if a is False]
    assert not missing, "paths cited at a commit that the commit does not hold:\n" + "\n".join(missing)


def test_every_bench_file_is_in_the_index():
    bench = ROOT / "docs" / "bench"
    index = (bench / "INDEX.md").read_text(encoding="utf-8")
    listed = {(bench / t).resolve() for t in LINK.findall(index) if not re.match(r"[a-z]+:|\.\./", t)}
    files = {p.resolve() for p in bench.rglob("*") if p.is_file() and p.name != "INDEX.md"}
    assert files, "docs/bench/ holds the cited measurement files"
    unlisted = sorted(str(p.relative_to(bench)) for p in files - listed)
    assert not unlisted, "files under docs/bench/ that INDEX.md does not list:\n" + "\n".join(unlisted)
