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
    record_bytes: int = 40  # a short typical record: sizes the walk's first record arrays (too few: twice)

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
    # 1.2, 1.3 and 1.4 print the same UAPs and items: one table serves them (the build checks it).
    # Not a measurement category yet: the pipeline's measurement model reads CAT048 and CAT021 only.
    Category(1, "Transmission of Monoradar Data Target Reports", "radar", "1.4",
             aliases={"1.2": "1.4", "1.3": "1.4", "1.x": "1.4"}, measurements=False, record_bytes=16),
    # 1.0, 1.1 and 1.2 print the same UAP and items; CAT002 gives CAT001 its whole time of day
    Category(2, "Transmission of Monoradar Service Messages", "radar service", "1.2",
             aliases={"1.0": "1.2", "1.1": "1.2", "1.x": "1.2"}, measurements=False, record_bytes=8),
    # system tracks: read as tracks under test, not fused as measurements (1.16-1.21; earlier editions
    # such as the pre-standard 0.17 differ in many items and are not decoded)
    Category(62, "SDPS Track Messages", "system track", "1.21", measurements=False),
    Category(19, "Multilateration System Status Messages", "MLAT status", "1.3", measurements=False),
    # 1.2 and 1.3 print the same UAP and item layouts
    Category(23, "CNS/ATM Ground Station and Service Status Reports", "ground station status", "1.3",
             aliases={"1.2": "1.3"}, measurements=False),
    Category(25, "CNS/ATM Ground System Status Reports", "ground system status", "1.5", measurements=False),
    Category(63, "Sensor Status Reports", "sensor status", "1.6", measurements=False),
    Category(65, "SDPS Service Status Messages", "SDPS service status", "1.5", measurements=False),
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
