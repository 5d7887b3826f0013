"""The docs cover what a user can set: every scene key appears in the user guide's tables."""
import dataclasses
import re
from pathlib import Path

from ngfrac.scene import LISTS, SECTIONS

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "user-guide.md"


def documented_keys():
    text = GUIDE.read_text()
    keys = {}
    for block in re.split(r"\n### ", text):
        header = re.match(r"`\[+([a-z_]+)\]+`", block)
        if not header:
            continue
        rows = re.findall(r"^\| ([^|]+) \|", block, flags=re.M)
        names = set()
        for row in rows:
            names.update(part.strip() for part in row.split(","))
        keys[header.group(1)] = names
    return keys


def test_every_scene_key_is_in_the_user_guide():
    keys = documented_keys()
    missing = []
    for section, cls in {**SECTIONS, **LISTS}.items():
        for field in dataclasses.fields(cls):
            if field.name not in keys.get(section, set()):
                missing.append(f"{section}.{field.name}")
    assert not missing, f"scene keys missing from docs/user-guide.md: {missing}"
