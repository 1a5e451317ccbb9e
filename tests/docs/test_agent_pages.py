"""The agents' index written from the families (``<!-- generated: agents -->``)."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys

from tests.docs.docs_tools import ROOT, TOOLS, load_tool

LINK = re.compile(r"\]\(([^)#]+)(?:#[^)]*)?\)")


def test_the_index_page_asks_for_the_generated_part() -> None:
    text = (ROOT / "docs" / "agents" / "index.md").read_text(encoding="utf-8")
    assert "<!-- generated: agents -->" in text.splitlines()


def test_one_section_per_family_in_catalog_order_and_one_row_per_agent() -> None:
    from skidnav.agents.catalog import families

    text = load_tool("generated_pages").agents_reference()
    headings = re.findall(r"^## The (\w+) family$", text, flags=re.MULTILINE)
    assert headings == [family.name for family in families()]
    for family in families():
        section = text.split(f"## The {family.name} family", 1)[1].split("\n## ", 1)[0]
        assert family.summary[1:] in section
        rows = re.findall(r"^\| `([\w-]+)` \| (.+?) \|", section, flags=re.MULTILINE)
        assert [name for name, _ in rows] == list(family.agents)
        assert all(described.endswith(".") for _, described in rows)
        for save_format in family.save_formats:
            assert f"`{save_format}`" in section


def test_every_link_of_the_generated_part_is_a_page() -> None:
    text = load_tool("generated_pages").agents_reference()
    links = LINK.findall(text)
    assert links
    for link in links:
        assert (ROOT / "docs" / "agents" / link).is_file(), link


def test_every_setting_of_every_agent_is_listed_with_its_meaning() -> None:
    from skidnav.agents.catalog import families

    text = load_tool("generated_pages").agents_reference()
    for family in families():
        for name in family.agents:
            config = family.config_class(name)
            block = text.split(f'??? note "`{name}`: its `params`', 1)[1].split("???", 1)[0]
            for field in dataclasses.fields(config):
                assert f"| `{field.name}` |" in block, (name, field.name)


def test_writing_the_agents_part_imports_no_deep_learning_library() -> None:
    script = (
        "import sys; sys.path.insert(0, sys.argv[1]); import generated_pages; "
        "generated_pages.agents_reference(); "
        "print(sorted({'torch', 'stable_baselines3'} & set(sys.modules)))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script, str(TOOLS)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert result.stdout.strip() == "[]"
