"""Which per-item figures a run draws (--figures-limit, --figures-only; track and conflicts) and the list of
those it does not draw, each with the command that draws it (``figures_not_drawn.txt`` beside them)."""

from __future__ import annotations

import difflib
import shlex
from dataclasses import dataclass
from pathlib import Path

from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.jobs.options import command_args

NOT_DRAWN = "figures_not_drawn.txt"


@dataclass(frozen=True)
class FigureChoice:
    """The figures a run has (file names, in order) and which of them it draws (indices)."""

    names: list[str]
    drawn: list[int]

    @property
    def not_drawn(self) -> list[str]:
        """The names left out, in order."""
        chosen = set(self.drawn)
        return [n for i, n in enumerate(self.names) if i not in chosen]


def only_names(text: str | None) -> list[str]:
    """--figures-only's names, each ending in .png; OptionError when it names none."""
    if text is None:
        return []
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    if not names:
        raise OptionError(f"--figures-only {text!r}: give figure file names, comma-separated")
    return [n if n.lower().endswith(".png") else f"{n}.png" for n in names]


def choose(names: list[str], limit: int, only: str | None) -> FigureChoice:
    """The figures to draw: those --figures-only names (OptionError naming one this run does not have, with
    the closest it has), else the first ``limit`` (0: all)."""
    wanted = only_names(only)
    if wanted:
        where = {n: i for i, n in enumerate(names)}
        for name in wanted:
            if name not in where:
                close = difflib.get_close_matches(name, names, n=3, cutoff=0.5)
                hint = f"closest: {', '.join(close)}" if close else f"this run has {len(names)} figure(s)"
                raise OptionError(f"--figures-only {name}: no such figure in this run; {hint}")
        return FigureChoice(names, sorted({where[n] for n in wanted}))
    count = len(names) if limit == 0 else min(int(limit), len(names))
    return FigureChoice(names, list(range(count)))


def draw_command(command: str, options: object, name: str) -> str:
    """The shell command that draws figure ``name`` of this run: the same options (so the same tracks and
    alerts), with --figures-only naming it; track's without -o and --json (not needed with --figures)."""
    changed = {"output": None, "json": None} if command == "track" else {}
    args = command_args(options, figures_only=name.removesuffix(".png"), **changed)
    return shlex.join(["msdc", command, *_without(args, "--figures-limit")])


def _without(args: list[str], flag: str) -> list[str]:
    """args with ``flag`` and its value left out."""
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
        elif a == flag:
            skip = True
        else:
            out.append(a)
    return out


def not_drawn_text(command: str, options: object, choice: FigureChoice) -> str:
    """figures_not_drawn.txt: why, how to draw them all, then one line per figure left out with the
    command that draws it."""
    left = choice.not_drawn
    every = shlex.join(["msdc", command, *command_args(options, figures_limit=0)])
    lines = [f"# {len(left)} of {len(choice.names)} figures not drawn (--figures-limit "
             f"{getattr(options, 'figures_limit', '')}); all of them: {every}",
             "# each line: the figure, then the command that draws it alone (the same run, --figures-only)"]
    lines += [f"{name}\t{draw_command(command, options, name)}" for name in left]
    return "\n".join(lines) + "\n"


def write_not_drawn(folder: Path, command: str, options: object, choice: FigureChoice) -> Path | None:
    """Write figures_not_drawn.txt in ``folder`` (the staged figures folder) when --figures-limit left
    figures out (not after --figures-only: its run draws what was asked for); its path, else None."""
    if not choice.not_drawn or getattr(options, "figures_only", None) is not None:
        return None
    path = Path(folder) / NOT_DRAWN
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(not_drawn_text(command, options, choice), encoding="utf-8")
    return path


def check_figure_options(options: object) -> None:
    """--figures-limit and --figures-only need --figures; --figures-only names something. OptionError."""
    if getattr(options, "figures", None) is None:
        for flag, value, default in (("--figures-limit", options.figures_limit, type(options).figures_limit),
                                     ("--figures-only", options.figures_only, None)):
            if value != default:
                raise OptionError(f"{flag} {value}: only with --figures DIR")
    only_names(options.figures_only)
