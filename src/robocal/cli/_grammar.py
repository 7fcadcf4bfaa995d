"""The command-line grammar's deprecated names (docs/cli.md): old option names keep working for
one release, with one ``Warning: --sigma is deprecated, use --noise`` line on stderr.

The aliases are not click options (so they stay out of ``--help``): each command's arguments are
rewritten before click parses them, by one table (:data:`DEPRECATED`) for the whole command line.
:func:`install` is called on every command as it is loaded (:class:`~robocal.cli._lazy.LazyGroup`).

Rules of a table entry ``{old: new}``:

* ``"--new"``: a plain rename (``--old V`` and ``--old=V``);
* ``("--new", n)``: the old option took ``n`` numbers separated by spaces, the new one takes them
  joined by commas (``--tcp 1 2 3`` becomes ``--tool 1,2,3``);
* ``ROBOT_ARGUMENT``: the old ``--robot NAME`` becomes the first positional argument;
* ``("--new", "value")``: the old option is renamed only when a value follows it (``--json FILE``
  becomes ``--summary FILE``; a plain ``--json`` stays the flag);
* ``("NAME", ARGUMENT)``: the old ``--images DIR`` becomes the positional argument ``NAME``, put
  after the others (``handeye solve``'s DATA);
* ``("--new", OLD_FILE)``: the old option named a file where the new one names a folder (``--plot
  FILE`` vs ``--plots DIR``): the old option stays a *hidden* option of the command, which still
  writes the file it names; the rewrite only warns.

An optional robot before a required argument (``thermal screen [ROBOT] RUN_DIR``) is declared with
:data:`OPTIONAL_ROBOT` in a command of class :class:`OptionalRobotCommand`: when the robot is left
out, an empty first argument is put in its place (click fills positional arguments from the left)
and becomes None.
"""

from __future__ import annotations

import click

__all__ = ["ARGUMENT", "DEPRECATED", "DEPRECATED_COMMANDS", "OLD_FILE", "OPTIONAL_ROBOT", "OptionalRobotCommand",
           "ROBOT_ARGUMENT", "install", "rewrite"]

ROBOT_ARGUMENT = "ROBOT"
#: rule kind: the old option becomes a positional argument (module docstring)
ARGUMENT = "argument"
#: rule kind: the old option named a file, the new one names a folder (module docstring)
OLD_FILE = "file"

#: command path (without ``robocal``) -> {old option: rule}
DEPRECATED: dict[str, dict] = {
    "calibrate": {"--sigma": "--noise", "--tolerance": "--time-tolerance", "--tool": ("--tool", 3)},
    "closed-chain calibrate": {"--sigma": "--noise"},
    "closed-chain simulate": {"--tolerance": "--distance-tolerance", "--joint-resolution": "--joint-noise"},
    "fk": {"--euler": "--orientation"},
    "ik": {"--euler": "--orientation"},
    "fleet status": {"--tolerance": "--distance-tolerance", "--tolerance-deg": "--angle-tolerance"},
    "fleet study monte-carlo": {"--json": ("--summary", "value"), "--tool": ("--tool", 3)},
    "fleet study pose-sets": {"--json": ("--summary", "value"), "--tool": ("--tool", 3)},
    "controller diff": {"--plot": ("--plots", OLD_FILE)},
    "fleet study thermal": {"--json": ("--summary", "value")},
    "handeye solve": {"--robot": ROBOT_ARGUMENT, "--images": ("DATA", ARGUMENT)},
    "history": {"--plot": ("--plots", OLD_FILE)},
    "import": {"--tolerance": "--time-tolerance", "--robot": ROBOT_ARGUMENT},
    "plan-poses": {"--tool": ("--tool", 3)},
    "self-calibrate": {"--tolerance": "--time-tolerance", "--joint-noise-deg": "--joint-noise"},
    "simulate self-calibration": {"--joint-noise-deg": "--joint-noise", "--joint-offsets-deg": "--joint-offsets",
                                  "--length-sigma-mm": "--length-sigma", "--board-bow-mm": "--board-bow",
                                  "--clock-offset-s": "--clock-offset", "--jitter-s": "--jitter",
                                  "--log-rate-hz": "--log-rate"},
    "simulate camera": {"--robot": ROBOT_ARGUMENT, "--pose-noise-mm": "--pose-noise", "--pose-noise-deg": "--pose-angle-noise",
                        "--joint-offset-sigma-deg": "--joint-offset-sigma"},
    "tcp accuracy": {"--first-seed": "--seed"},
    "tcp cross-laser": {"--convention": "--orientation"},
    "tcp seven-point": {"--tcp": ("--tool", 3)},
    "tcp simulate": {"--robot": ROBOT_ARGUMENT, "--events-out": ("--out", OLD_FILE), "--sensor-out": ("--out", OLD_FILE)},
    "thermal calibrate-sensor": {"--sigma": "--noise"},
    "thermal compensate": {"--sigma": "--noise", "--history": "--db"},
    "thermal experiment": {"--first-seed": "--seed"},
    "thermal screen": {"--robot": ROBOT_ARGUMENT, "--threshold-mm": "--threshold"},
}

#: group path -> {old command name: new command name}
DEPRECATED_COMMANDS: dict[str, dict] = {"tcp": {"sensor-calibrate": "calibrate-sensor"}}


def _none_if_empty(ctx, param, value):
    return value or None


#: keyword arguments of ``click.argument("robot", **OPTIONAL_ROBOT)``: an optional first argument
#: before required ones (see the module docstring)
OPTIONAL_ROBOT = {"required": False, "default": None, "callback": _none_if_empty}


def _given(value) -> bool:
    """A parsed argument value that came from the command line (not None, not click's UNSET)."""
    return value is not None and type(value).__name__ != "Sentinel"


def _with_robot_slot(command: click.Command, ctx, args: list) -> list:
    """``args`` with an empty first argument when the optional robot of ``command`` is left out."""
    first = next((p for p in command.params if isinstance(p, click.Argument)), None)
    if first is None or first.name != "robot" or first.required:
        return args
    n_required = sum(1 for p in command.params if isinstance(p, click.Argument) and p.required)
    if n_required == 0:
        return args
    try:
        values, rest, _ = command.make_parser(ctx).parse_args(args=list(args))
    except click.UsageError:
        return args  # click reports it when it parses for real
    given = sum(_given(values.get(p.name)) for p in command.params if isinstance(p, click.Argument)) + len(rest)
    return [""] + list(args) if given == n_required else args


class OptionalRobotCommand(click.Command):
    """A command whose first argument is an optional ROBOT before required arguments."""

    def parse_args(self, ctx, args):
        if not ("--help" in args or "-h" in args):
            args = _with_robot_slot(self, ctx, args)
        return super().parse_args(ctx, args)


def _warn(old: str, new: str) -> None:
    click.echo(f"Warning: {old} is deprecated, use {new}", err=True)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def rewrite(args: list, rules: dict) -> list:
    """``args`` with the deprecated options of ``rules`` replaced by their new form (a warning
    each); everything after ``--`` is left alone."""
    out, robot, arguments, i = [], None, [], 0
    args = list(args)
    while i < len(args):
        token = args[i]
        if token == "--":
            out += args[i:]
            break
        name, eq, value = token.partition("=")
        rule = rules.get(name)
        if rule is None:
            out.append(token)
            i += 1
            continue
        if rule == ROBOT_ARGUMENT:
            _warn(name, "the first argument ROBOT")
            if eq:
                robot, i = value, i + 1
            else:
                robot, i = (args[i + 1] if i + 1 < len(args) else None), i + 2
            continue
        if isinstance(rule, str):
            _warn(name, rule)
            out.append(rule + eq + value)
            i += 1
            continue
        new, how = rule
        if how == ARGUMENT:  # --images DIR -> the positional argument DATA
            _warn(name, f"the argument {new}")
            if eq:
                arguments.append(value)
                i += 1
            else:
                arguments += args[i + 1:i + 2]
                i += 2
            continue
        if how == OLD_FILE:  # a hidden option of the command: it still writes the file it names
            _warn(f"{name} FILE", f"{new} DIR")
            out.append(token)
            i += 1
            continue
        if how == "value":  # renamed only with a value: --json FILE -> --summary FILE
            if eq or (i + 1 < len(args) and not args[i + 1].startswith("-")):
                _warn(f"{name} FILE", f"{new} FILE")
                out += [new + eq + value] if eq else [new, args[i + 1]]
                i += 1 if eq else 2
            else:
                out.append(token)
                i += 1
            continue
        n = int(how)  # n numbers separated by spaces -> joined by commas
        values = args[i + 1:i + 1 + n]
        if not eq and len(values) == n and all(_is_number(v) for v in values):
            _warn(f"{name} {' '.join(['V'] * n)}", f"{new} {','.join(['V'] * n)}")
            out += [new, ",".join(values)]
            i += 1 + n
        else:
            out.append(new + eq + value if name != new else token)
            i += 1
    if arguments and "--" in out:
        cut = out.index("--")
        out = out[:cut] + arguments + out[cut:]
    else:
        out += arguments
    return ([robot] if robot is not None else []) + out


def _deprecated_command(command: click.Command, old: str, new: str) -> click.Command:
    """A hidden twin of ``command`` under its old name that warns, then runs it."""
    callback = command.callback

    def run(*args, **kwargs):
        _warn(old, new)
        return callback(*args, **kwargs)

    return click.Command(old, params=command.params, callback=run, hidden=True, help=command.help,
                         context_settings=command.context_settings)


def install(command: click.Command, path: str) -> None:
    """Apply the tables to ``command`` (called ``path``, e.g. ``"tcp seven-point"``) and its
    sub-commands."""
    if isinstance(command, click.Group):
        for old, new in DEPRECATED_COMMANDS.get(path, {}).items():
            if new in command.commands and old not in command.commands:
                command.add_command(_deprecated_command(command.commands[new], old, f"{path} {new}"), old)
        for name, sub in list(command.commands.items()):
            if not sub.hidden:
                install(sub, f"{path} {name}")
        return
    rules = DEPRECATED.get(path)
    if not rules or getattr(command, "_grammar_installed", False):
        return
    parse_args = command.parse_args

    def parse_with_aliases(ctx, args):
        return parse_args(ctx, rewrite(args, rules))

    command.parse_args = parse_with_aliases
    command._grammar_installed = True


class CommaFloats(click.ParamType):
    """``X,Y,Z`` (and with ``sizes=(3, 6)`` also ``X,Y,Z,A,B,C``): numbers separated by commas, as a
    tuple of floats (``--tool``, ``--base``)."""

    name = "numbers"

    def __init__(self, sizes=(3,)):
        self.sizes = tuple(sizes)

    def convert(self, value, param, ctx):
        if isinstance(value, (tuple, list)):
            parts = list(value)
        else:
            parts = [p for p in str(value).replace(" ", ",").split(",") if p]
        try:
            numbers = tuple(float(p) for p in parts)
        except ValueError:
            self.fail(f"{value!r}: expected numbers separated by commas", param, ctx)
        if len(numbers) not in self.sizes:
            self.fail(f"{value!r}: expected {' or '.join(str(n) for n in self.sizes)} numbers separated by commas",
                      param, ctx)
        return numbers


#: ``--tool X,Y,Z`` (a point in the flange frame [mm])
POINT = CommaFloats((3,))
