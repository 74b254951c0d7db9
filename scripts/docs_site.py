#!/usr/bin/env python3
"""The documentation site's pages and its link checks (scripts/docs.sh; standard library only).

    docs_site.py check-md ROOT            every relative link of the Markdown pages points to an
                                          existing file, and every #anchor to a heading there;
                                          docs/index.md links every page under docs/
    docs_site.py pages ROOT OUT           the page tree FORD's page_dir reads: the pages with their
                                          title metadata, links to pages rewritten to .html
    docs_site.py check-html SITE          every relative link of the site's pages (SITE/page)
                                          points to an existing file and anchor

The pages are README.md, CHANGELOG.md, every Markdown file under docs/ (not docs/ford.md, FORD's
project file) and the READMEs of jobs/, tools/ and tests/. They stay plain GitHub Markdown; the
tree mirrors the repository (a README.md becomes its directory's index.md, so README.md is the
site's front page), every heading gets the id GitHub gives it, and every other file a page links
to is copied beside it. Each check prints one line per broken link and exits 1 if there is any.
"""
from __future__ import annotations

import html.parser
import os
import re
import shutil
import sys
from pathlib import Path

LINK = re.compile(r"(!?\[(?:[^\[\]]|\[[^\]]*\])*\])\(\s*([^()\s]+)(\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")
EXTERNAL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def page_files(root: Path) -> list[Path]:
    """The Markdown pages of the site, relative to the repository's top."""
    pages = [Path("README.md"), Path("CHANGELOG.md")]
    pages += sorted(p.relative_to(root) for p in (root / "docs").rglob("*.md")
                    if p.relative_to(root) != Path("docs/ford.md"))
    pages += [Path(d) / "README.md" for d in ("jobs", "tools", "tests")]
    return [p for p in pages if (root / p).is_file()]


def site_path(page: Path) -> Path:
    """Where a page goes in the page tree (a README.md is its directory's index.md)."""
    return page.with_name("index.md") if page.name == "README.md" else page


def text_lines(text: str) -> list[tuple[int, str]]:
    """The numbered lines outside fenced and indented code blocks."""
    out = []
    fenced = False
    previous_blank = True
    for number, line in enumerate(text.split("\n"), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        indented = line.startswith("    ") and previous_blank
        previous_blank = (line.strip() == "") or (indented and previous_blank)
        if fenced or indented:
            continue
        out.append((number, line))
    return out


def without_code_spans(line: str) -> str:
    return re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), line)


def heading_text(raw: str) -> str:
    """The text of a heading as GitHub slugs it: links reduced to their text, no emphasis."""
    raw = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", raw)
    return raw.replace("`", "").replace("*", "")


def github_slug(text: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation but - and _ removed, spaces to -."""
    slug = re.sub(r"[^\w\- ]", "", heading_text(text).strip().lower())
    return slug.replace(" ", "-")


def anchors(text: str) -> list[str]:
    """The anchors of a page's headings, duplicates numbered as GitHub numbers them."""
    seen: dict[str, int] = {}
    out = []
    for _, line in text_lines(text):
        m = HEADING.match(line)
        if m:
            out.append(unique_slug(m.group(2), seen))
    return out


def unique_slug(heading: str, seen: dict[str, int]) -> str:
    """The GitHub anchor of `heading`, numbered when `seen` (the page's anchors so far, updated
    here) already has it."""
    slug = github_slug(heading)
    if slug in seen:
        seen[slug] += 1
        return f"{slug}-{seen[slug]}"
    seen[slug] = 0
    return slug


def links(text: str) -> list[tuple[int, str]]:
    """(line, target) of every inline link and image outside code."""
    out = []
    for number, line in text_lines(text):
        for m in LINK.finditer(without_code_spans(line)):
            out.append((number, m.group(2)))
    return out


def check_markdown(root: Path) -> list[str]:
    problems = []
    page_anchors: dict[Path, list[str]] = {}   # each linked page's anchors, read once
    for page in page_files(root):
        text = (root / page).read_text(encoding="utf-8")
        for number, target in links(text):
            if EXTERNAL.match(target):
                continue
            path_part, _, anchor = target.partition("#")
            dest = (root / page).parent / path_part if path_part else root / page
            where = f"{page}:{number}: link '{target}'"
            if not dest.exists():
                problems.append(where + ": no such file")
                continue
            if anchor and dest.suffix == ".md" and dest not in page_anchors:
                page_anchors[dest] = anchors(dest.read_text(encoding="utf-8"))
            if anchor and dest.suffix == ".md" and anchor not in page_anchors[dest]:
                problems.append(where + ": no heading with that anchor in " +
                                os.path.relpath(dest, root))
    index = root / "docs" / "index.md"
    if index.is_file():
        linked = {os.path.normpath(index.parent / t.partition("#")[0])
                  for _, t in links(index.read_text(encoding="utf-8")) if not EXTERNAL.match(t)}
        for page in page_files(root):
            if page.parts[0] == "docs" and page != Path("docs/index.md") and \
                    os.path.normpath(root / page) not in linked:
                problems.append(f"docs/index.md: no link to the page {page}")
    return problems


def rewrite(text: str, page: Path, root: Path, pages: set[Path], copies: set[Path]) -> str:
    """Links to pages point to their .html; other linked files are noted for copying."""
    lines = text.split("\n")
    code_lines = set(range(1, len(lines) + 1)) - {n for n, _ in text_lines(text)}
    seen: dict[str, int] = {}
    for index, line in enumerate(lines):
        number = index + 1
        if number in code_lines:
            continue
        m = HEADING.match(line)
        if m and not line.rstrip().endswith("}"):
            line = f"{m.group(1)} {m.group(2)} {{: #{unique_slug(m.group(2), seen)} }}"
        masked = without_code_spans(line)
        pieces = []
        last = 0
        for lm in LINK.finditer(masked):
            target = lm.group(2)
            if EXTERNAL.match(target) or target.startswith("#"):
                continue
            path_part, sep, anchor = target.partition("#")
            dest = Path(os.path.normpath(page.parent / path_part))
            if dest in pages:
                new = os.path.relpath(site_path(dest).with_suffix(".html"),
                                      site_path(page).parent)
            else:
                copies.add(dest)
                new = os.path.relpath(dest, site_path(page).parent)
            pieces.append(line[last:lm.start(2)] + new + sep + anchor)
            last = lm.end(2)
        lines[index] = "".join(pieces) + line[last:]
    return "\n".join(lines)


def title_of(text: str, page: Path) -> str:
    for _, line in text_lines(text):
        m = HEADING.match(line)
        if m and len(m.group(1)) == 1:
            return heading_text(m.group(2)).strip()
    return str(page)


def site_name(directory: Path, entry: str) -> str:
    """The site's name of a directory entry in a generated index: pages as .html."""
    if (directory / entry).is_dir():
        return entry + "/index.html"
    return entry[:-3] + ".html" if entry.endswith(".md") else entry


def build_pages(root: Path, out: Path) -> None:
    if out.exists():
        shutil.rmtree(out)
    pages = set(page_files(root))
    copies: set[Path] = set()
    for page in sorted(pages):
        text = (root / page).read_text(encoding="utf-8")
        target = out / site_path(page)
        target.parent.mkdir(parents=True, exist_ok=True)
        body = rewrite(text, page, root, pages, copies)
        target.write_text(f"title: {title_of(text, page)}\n\n{body}", encoding="utf-8")
    for item in sorted(copies):
        src = root / item
        dest = out / item
        dest.parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir():
            shutil.copytree(src, dest, dirs_exist_ok=True)
        else:
            shutil.copy(src, dest)
    # FORD needs an index.md in every directory of the tree: a list of what it holds.
    for directory in sorted(d for d in out.rglob("*") if d.is_dir()):
        index = directory / "index.md"
        if index.exists():
            continue
        rel = directory.relative_to(out)
        entries = sorted(p.name for p in directory.iterdir() if p.name != "index.md")
        items = "\n".join(f"- [{e}]({site_name(directory, e)})" for e in entries)
        index.write_text(f"title: {rel}\n\nFiles in `{rel}`:\n\n{items}\n", encoding="utf-8")


class _Page(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.refs: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        for key in ("id", "name"):
            if values.get(key) and (key == "id" or tag == "a"):
                self.ids.add(values[key] or "")
        for key in ("href", "src"):
            if (tag in ("a", "img") or key == "href" and tag == "link") and values.get(key):
                self.refs.append(values[key] or "")


def _parse(path: Path) -> _Page:
    parser = _Page()
    parser.feed(path.read_text(encoding="utf-8", errors="replace"))
    return parser


def check_html(site: Path) -> list[str]:
    problems = []
    cache: dict[Path, _Page] = {}
    for page in sorted((site / "page").rglob("*.html")):
        parsed = cache.setdefault(page, _parse(page))
        for ref in parsed.refs:
            if EXTERNAL.match(ref) or ref.startswith("//"):
                continue
            path_part, _, anchor = ref.partition("#")
            path_part = path_part.split("?")[0]
            dest = (page.parent / path_part).resolve() if path_part else page
            where = f"{page.relative_to(site)}: link '{ref}'"
            if not dest.exists():
                problems.append(where + ": no such file")
            elif (anchor and dest.suffix == ".html"
                  and anchor not in cache.setdefault(dest, _parse(dest)).ids):
                problems.append(where + ": no element with that id")
    return problems


def main(argv: list[str]) -> int:
    if len(argv) == 2 and argv[0] == "check-md":
        problems = check_markdown(Path(argv[1]))
        what = "Markdown pages"
    elif len(argv) == 3 and argv[0] == "pages":
        build_pages(Path(argv[1]), Path(argv[2]))
        return 0
    elif len(argv) == 2 and argv[0] == "check-html":
        problems = check_html(Path(argv[1]))
        what = "site pages"
    else:
        sys.stderr.write(__doc__ or "")
        return 2
    for problem in problems:
        print("broken link: " + problem)
    print(f"{what}: {len(problems)} broken link(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
