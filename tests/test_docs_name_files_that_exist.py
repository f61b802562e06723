"""The README and docs/ name only Markdown files that are there (outputs under out/ aside): a
reader following "see X.md" finds it."""

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_every_markdown_file_the_docs_name_exists() -> None:
    missing = []
    for doc in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for name in re.findall(r"[\w./-]+\.md\b", doc.read_text()):
            if name.startswith("out/"):  # written by a run, not shipped
                continue
            if not ((doc.parent / name).exists() or (REPO / name).exists()):
                missing.append(f"{doc.relative_to(REPO)}: {name}")
    assert missing == []
