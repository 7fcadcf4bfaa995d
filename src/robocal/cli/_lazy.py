"""A click group that imports a command's module only when that command is used.

``robocal --help`` lists every command from a table of one-line summaries without importing
any of them; ``robocal robots`` imports only ``cli/kinematics.py``. This keeps start-up free of
numba, scipy and matplotlib for the commands that need no kernels.
"""

from __future__ import annotations

import importlib

import click


class LazyGroup(click.Group):
    """``click.Group`` with commands given as ``{name: (module, attribute, summary, hook)}``.

    ``module`` is relative to ``robocal.cli``; ``hook`` (or None) is called with the command once
    it is loaded (e.g. to attach subcommands that live in another module). Commands added with
    ``add_command`` / ``@group.command`` work as usual.
    """

    def __init__(self, *args, lazy_commands=None, **kwargs):
        super().__init__(*args, **kwargs)
        self.lazy_commands = dict(lazy_commands or {})

    def list_commands(self, ctx) -> list[str]:
        return sorted(set(super().list_commands(ctx)) | set(self.lazy_commands))

    def get_command(self, ctx, cmd_name):
        if cmd_name not in self.commands and cmd_name in self.lazy_commands:
            self.commands[cmd_name] = self._load(cmd_name)
        return super().get_command(ctx, cmd_name)

    def _load(self, name: str) -> click.Command:
        module, attribute, summary, hook = self.lazy_commands[name]
        command = getattr(importlib.import_module(f"{__package__}.{module}"), attribute)
        command.short_help = summary
        if hook is not None:
            hook(command)
        from ._grammar import install

        install(command, name)  # the deprecated option names of docs/cli.md
        return command

    def format_commands(self, ctx, formatter) -> None:
        """The command list from the summaries, without importing the commands' modules."""
        rows = []
        for name in self.list_commands(ctx):
            if name in self.commands:
                command = self.commands[name]
                if command.hidden:
                    continue
                rows.append((name, command.get_short_help_str(limit=10_000)))
            else:
                rows.append((name, self.lazy_commands[name][2]))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)
