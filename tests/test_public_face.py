"""``import msdc``: every command's job is a public name, and the library reference documents each job with
its options and result (a command added later without them fails here)."""

from __future__ import annotations

import argparse
import importlib
import inspect
from pathlib import Path

import pytest

import msdc
from msdc.pipeline.cli import build_parser

API = (Path(__file__).resolve().parents[1] / "docs" / "api.md").read_text()


def _commands() -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return list(sub.choices)


def _job(command: str):
    """The command's module and its one public ``*_job`` function."""
    module = importlib.import_module(f"msdc.pipeline.jobs.{command}")
    jobs = [name for name in module.__all__
            if name.endswith("_job") and inspect.isfunction(getattr(module, name))]
    assert len(jobs) == 1, (command, jobs)
    return module, jobs[0]


def test_the_cli_has_the_eleven_commands_the_docs_list():
    assert _commands() == ["decode", "stats", "correlate", "quality", "track", "conflicts", "evaluate",
                           "ingest", "sql", "listen", "replay"]


@pytest.mark.parametrize("command", _commands())
def test_each_command_s_job_is_a_name_of_msdc(command):
    module, name = _job(command)
    assert name in msdc.__all__ and name in dir(msdc)
    assert getattr(msdc, name) is getattr(module, name)


@pytest.mark.parametrize("command", _commands())
def test_the_library_reference_documents_each_job_its_options_and_result(command):
    module, name = _job(command)
    path = f"msdc.pipeline.jobs.{command}"
    documented = {line.removeprefix("::: ").strip() for line in API.splitlines() if line.startswith("::: ")}
    options = [n for n in module.__all__ if n.endswith("Options")]
    results = [n for n in module.__all__ if n.endswith("Result")]
    assert len(options) == 1 and len(results) == 1, (command, options, results)
    for n in (name, *options, *results):
        assert f"{path}.{n}" in documented, f"docs/api.md lacks ::: {path}.{n}"
    assert f"`msdc.{name}`" in API  # in the table of the public face


def test_a_name_msdc_does_not_have_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'evaluate'"):
        msdc.evaluate  # noqa: B018
