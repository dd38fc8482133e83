#!/usr/bin/env python3
"""Check the built book's internal links (scripts/ci-book.sh runs it after `mdbook build`).

Walks every .html file under the build directory and fails, naming the file and the link, for
any relative href or src whose target file does not exist, or whose #anchor is not an id (or a
name) in the target. mdbook itself only warns about missing chapters, and a Markdown link that
leaves book/src renders as a link that is broken in the HTML; this catches both.
Python 3, standard library only.
"""
import os
import sys
from html.parser import HTMLParser
from urllib.parse import unquote, urlsplit


class Page(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids = set()
        self.links = []  # (attribute, value)

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if value is None:
                continue
            if name in ("id", "name"):
                self.ids.add(value)
            elif name == "href" or (name == "src" and tag in ("img", "script", "iframe")):
                self.links.append((name, value))


def parse(path, cache):
    if path not in cache:
        page = Page()
        with open(path, encoding="utf-8", errors="replace") as f:
            page.feed(f.read())
        cache[path] = page
    return cache[path]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "book/book")
    if not os.path.isdir(root):
        sys.exit(f"check-book-links: no built book at {root} (run mdbook build first)")
    cache, broken, checked = {}, [], 0
    for dirpath, _, files in os.walk(root):
        for name in sorted(files):
            if not name.endswith(".html"):
                continue
            here = os.path.join(dirpath, name)
            for _, link in parse(here, cache).links:
                parts = urlsplit(link)
                if parts.scheme or parts.netloc or link.startswith(("mailto:", "javascript:")):
                    continue  # external: not this checker's business
                checked += 1
                target = here
                if parts.path.startswith("/"):
                    # Site-absolute (404.html's links, site-url "/"): from the book's root.
                    target = os.path.normpath(os.path.join(root, unquote(parts.path).lstrip("/")))
                elif parts.path:
                    target = os.path.normpath(os.path.join(dirpath, unquote(parts.path)))
                    if parts.path.endswith("/") or os.path.isdir(target):
                        target = os.path.join(target, "index.html")
                rel = os.path.relpath(here, root)
                if not os.path.exists(target):
                    broken.append(f"{rel}: {link}: no file {os.path.relpath(target, root)}")
                    continue
                if parts.fragment and target.endswith(".html"):
                    if unquote(parts.fragment) not in parse(target, cache).ids:
                        broken.append(f"{rel}: {link}: no id #{parts.fragment} in "
                                      f"{os.path.relpath(target, root)}")
    for line in broken:
        print(line)
    print(f"check-book-links: {checked} internal links checked, {len(broken)} broken",
          file=sys.stderr)
    sys.exit(1 if broken else 0)


if __name__ == "__main__":
    main()
