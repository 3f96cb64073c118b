"""The jobs: one module per command (``decode``, ``stats``, ``correlate``, ``quality``, ``track``,
``conflicts``) as library calls that the CLI, notebooks and any other front end share; ``common`` holds what
they share (errors, option checks, loading the inputs).

Each job takes options validated before anything is decoded (the module's ``validate``: every option, the
sensor file and the output paths, each failure an ``OptionError`` naming the option or file and what is
allowed) and returns a result object holding the run's warnings (``warnings``, validation's first; an error
leaving a job carries those said before it: ``common.carrying``); writing the outputs is a separate call.
This package imports nothing itself: ``msdc --help`` loads no job, and each command only its own module.
"""
