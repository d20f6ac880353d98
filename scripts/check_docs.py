"""The documentation's checks (test docs/links): every relative link and image in README.md and
docs/**/*.md resolves to a file or folder of the repository, and README.md, the front door, stays
within 200 lines. Prints what it checked; exits 1 naming each broken link.
    /usr/bin/python3 scripts/check_docs.py [repository root]
"""
import os
import re
import sys

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
README_LINES = 200


def markdown_files(root):
    yield os.path.join(root, "README.md")
    for folder, _dirs, files in os.walk(os.path.join(root, "docs")):
        for f in sorted(files):
            if f.endswith(".md"):
                yield os.path.join(folder, f)


def broken_links(path):
    """(line number, target) of each relative link in `path` that does not resolve."""
    bad, in_code = [], False
    with open(path, encoding="utf-8") as fh:
        for number, line in enumerate(fh, 1):
            if line.lstrip().startswith("```"):
                in_code = not in_code
            if in_code:
                continue
            for target in LINK.findall(line):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                    continue  # a URL (https:, mailto:) or an anchor in the same file
                local = target.split("#", 1)[0]
                if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(path), local))):
                    bad.append((number, target))
    return bad


def main(root):
    files, links_bad = list(markdown_files(root)), []
    for path in files:
        links_bad += [(os.path.relpath(path, root), n, t) for n, t in broken_links(path)]
    with open(os.path.join(root, "README.md"), encoding="utf-8") as fh:
        readme = sum(1 for _ in fh)
    print(f"docs: {len(files)} markdown files checked; README.md has {readme} lines (at most {README_LINES})")
    for path, n, target in links_bad:
        print(f"docs: {path}:{n}: the link '{target}' leads nowhere")
    ok = not links_bad and readme <= README_LINES
    if readme > README_LINES:
        print(f"docs: README.md is {readme} lines, above {README_LINES}: move detail to docs/")
    print("docs: " + ("all good" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")))
