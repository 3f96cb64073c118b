"""tests/prewarm.py swallows its commands' failures: each must at least parse, or its kernels are never
compiled before the workers need them (its conflicts command once lacked -o)."""

import pytest
from prewarm import commands

from msdc.pipeline.cli import build_parser


@pytest.mark.parametrize("argv", commands("/tmp/out"), ids=lambda argv: argv[0])
def test_prewarm_commands_parse(argv: list[str]) -> None:
    args = build_parser().parse_args(argv)
    assert args.command == argv[0]
