"""The docs' tables of requirement ids and shipped presets, generated from the catalogue and the TOML files
(``python -m msdc.pipeline.evaluate.presets_doc --write-docs`` rewrites them in docs/methods/evaluate.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.evaluate.presets import available_presets, load_preset

PAGE = Path("docs") / "methods" / "evaluate.md"  # relative to a checkout: the docs are not installed
MARKERS = {"ids": ("<!-- requirement ids -->\n", "<!-- /requirement ids -->"),
           "presets": ("<!-- presets -->\n", "<!-- /presets -->")}


def _cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return text.replace("|", "\\|")


def ids_table() -> str:
    """The requirement ids a preset may name: kind, unit, parameters and meaning."""
    rows = ["| id | kind | unit | parameters | measures |", "|---|---|---|---|---|"]
    for ident, kind in CATALOGUE.items():
        params = ", ".join(f"`{p}`" + ("" if p in kind.required else " (optional)") for p in kind.parameters)
        meaning = _cell(kind.description)
        rows.append(f"| `{ident}` | {kind.kind} | {kind.unit} | {params or '-'} | {meaning} |")
    return "\n".join(rows) + "\n"


def presets_tables() -> str:
    """One table per shipped preset: requirement, area, figure as stated, threshold, clause, checked."""
    out = []
    for name in available_presets():
        preset = load_preset(name)
        out += [f"#### `{name}`: {_cell(preset.title)}", "",
                f"{_cell(preset.standard)}; sensors: {', '.join(preset.sensor_types)}; minimum sample: "
                f"{preset.min_sample if preset.min_sample else 'none stated'}."
                + (f" {_cell(preset.note)}" if preset.note else ""), "",
                "| requirement | area | parameters | stated | threshold | clause | checked |",
                "|---|---|---|---|---|---|---|"]
        for r in preset.requirements:
            params = ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                               for k, v in r.parameters.items())
            checked = "yes" if r.checked else "**no**"
            out.append(f"| `{r.id}` | {r.area or 'all'} | {params or '-'} | {_cell(r.stated)} | "
                       f"{r.direction} {r.threshold:g} | {_cell(r.clause)} | {checked} |")
        out.append("")
    return "\n".join(out)


def page_with_tables(text: str) -> str:
    """The page text with both generated sections replaced between their markers."""
    for key, body in (("ids", ids_table()), ("presets", presets_tables())):
        start, end = MARKERS[key]
        head, found, rest = text.partition(start)
        if not found or end not in rest:
            raise ValueError(f"{PAGE}: markers {start.strip()} ... {end} not found")
        text = head + start + body + end + rest.partition(end)[2]
    return text


def main(argv: list[str] | None = None) -> int:
    """``--write-docs`` rewrites the tables of docs/methods/evaluate.md; ``--check`` says if they differ."""
    parser = argparse.ArgumentParser(prog="python -m msdc.pipeline.evaluate.presets_doc",
                                     description=main.__doc__)
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--write-docs", action="store_true", help="rewrite the tables")
    what.add_argument("--check", action="store_true", help="exit 1 when the page's tables differ")
    parser.add_argument("--page", type=Path, default=PAGE,
                        help="the page (default: %(default)s, run from the checkout)")
    args = parser.parse_args(argv)
    check, page = args.check, args.page
    if not page.is_file():
        parser.error(f"--page {page}: no such file (run from the checkout's top folder)")
    text = page.read_text()
    new = page_with_tables(text)
    if new != text and not check:
        page.write_text(new)
    if new != text:
        print(f"{page}: {'differs from the presets' if check else 'rewritten'}")
    return 1 if new != text and check else 0


if __name__ == "__main__":
    sys.exit(main())
