"""The category registry: every ASTERIX category msdc decodes, with what it carries and how it is read.

One entry per category, in the order msdc reports them (radar first). The decoder, the jobs and the
command line take their category lists, default editions, edition aliases and wording from here, so a
new category is one entry plus its edition tables.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Category:
    """One decodable category: its number, what it carries, its editions and whether it is a source of
    measurements (decoded by default) or only read on request."""

    number: int
    title: str  # the specification's title
    noun: str  # what a user calls its reports in a message: "radar", "ADS-B"
    default_edition: str  # the table used when no edition is pinned
    aliases: dict[str, str] = field(default_factory=dict)  # edition -> shipped table with the same layout
    measurements: bool = True  # decoded when no category is asked for; feeds correlate/quality/track

    @property
    def label(self) -> str:
        """'CAT048'."""
        return f"CAT{self.number:03d}"


REGISTRY: dict[int, Category] = {c.number: c for c in (
    Category(48, "Monoradar Target Reports", "radar", "1.32",
             # 1.21-1.26 share the UAP and item layouts of 1.27 (the printed specs start at 1.27)
             aliases={**{f"1.{m}": "1.27" for m in range(21, 27)}, "1.x": "1.32"}),
    Category(21, "ADS-B Target Reports", "ADS-B", "2.7", aliases={"2.x": "2.7", "0.x": "0.26"}),
    # surface radar and airport multilateration in one category: I010/020 TYP says which per report
    Category(10, "Monosensor Surface Movement Data", "surface movement", "1.1"),
    Category(20, "Multilateration Target Reports", "multilateration", "1.11", aliases={"1.x": "1.11"}),
    Category(34, "Monoradar Service Messages", "radar service", "1.29", measurements=False),
)}

DECODABLE: tuple[int, ...] = tuple(sorted(REGISTRY))
MEASUREMENT_CATEGORIES: tuple[int, ...] = tuple(c for c, info in REGISTRY.items() if info.measurements)


def category(number: int) -> Category:
    """The registry entry of ``number``; KeyError naming the decodable categories when msdc has none."""
    try:
        return REGISTRY[number]
    except KeyError:
        known = ", ".join(c.label for c in REGISTRY.values())
        raise KeyError(f"CAT{number:03d} is not decoded by msdc (it decodes {known})") from None
