"""The reference tables generated from the code, as Markdown text (no Sphinx here, so
the tests can check them: tests/test_cli.py).

- :func:`config_markdown`: the configuration keys, from ``coupling.options.DEFAULTS``,
  ``CHOICES``, ``DATA_VARIABLES`` and the validation code, with the descriptions of
  docs/guide/keys.toml.
- :func:`cli_markdown`: the subcommands and options of ``coupling.app.cli.build_parser``.
- :func:`exit_codes_markdown`: the ``EXIT_*`` constants of ``coupling.app.ending`` with
  their meaning.
- :func:`errors_markdown`: bad configurations and the one-line error each one gets.
"""
from __future__ import annotations

import argparse
import json
import tomllib
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parents[2]
KEYS = DOCS / "guide" / "keys.toml"
EXIT_CODES = DOCS / "guide" / "exit_codes.toml"
ERRORS = DOCS / "guide" / "errors.toml"

#: A value of the wrong kind for each type of default: the validation's message for it
#: states the key's constraint.
_BAD = {bool: '"x"', int: "-1", float: "-1.0", str: '"?"', list: "[1]"}


def _toml(value: Any) -> str:
    """A default written as TOML."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ").strip()


def constraint(section: str, key: str) -> str:
    """What the validation requires of ``section.key``: its message for a bad value
    (without the key's name and the bad value), or "" when it accepts any value of the
    default's type at this stage."""
    from coupling.app.config import load_config
    from coupling.options import DEFAULTS

    bad = _BAD[type(DEFAULTS[section][key])]
    try:
        load_config(None, [f"{section}.{key}={bad}"])
    except ValueError as err:
        text = str(err).splitlines()[0]
        name = f"{section}.{key}"
        if text.startswith(name):
            text = text[len(name) :].lstrip()
        return text.rsplit(", got ", 1)[0]
    return ""


def _kind(section: str, key: str, default: Any) -> str:
    from coupling.options import CHOICES, DATA_VARIABLES, DATA_VARIABLES_3D

    if (section, key) in CHOICES:
        return "one of " + ", ".join(f'`"{c}"`' for c in CHOICES[section, key])
    if section == "data" and key in DATA_VARIABLES:
        planar = ", ".join(f"`{v}`" for v in DATA_VARIABLES[key])
        solid = ", ".join(f"`{v}`" for v in DATA_VARIABLES_3D[key])
        return f"expression in {planar}; for a body in R^3 in {solid}"
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "list"}[
        type(default)
    ]


def config_markdown(section: str, descriptions: Path = KEYS) -> str:
    """The table of the keys of one section of ``DEFAULTS``."""
    from coupling.options import CHOICES, DEFAULTS

    text = tomllib.loads(descriptions.read_text())
    missing = [f"{s}.{k}" for s, t in DEFAULTS.items() for k in t if k not in text.get(s, {})]
    extra = [f"{s}.{k}" for s, t in text.items() for k in t if k not in DEFAULTS.get(s, {})]
    if missing or extra:
        raise ValueError(
            f"{descriptions}: describe every configuration key of coupling.options.DEFAULTS "
            f"(missing: {', '.join(missing) or 'none'}; no such key: {', '.join(extra) or 'none'})"
        )
    out = ["| key | default | type | validation | meaning |", "|---|---|---|---|---|"]
    for key, default in DEFAULTS[section].items():
        out.append(
            f"| `{section}.{key}` | `{_toml(default)}` | {_kind(section, key, default)} "
            f"| {'' if (section, key) in CHOICES else _cell(constraint(section, key))} "
            f"| {_cell(text[section][key])} |"
        )
    return "\n".join(out) + "\n"


def _usage(parser: argparse.ArgumentParser) -> str:
    return " ".join(parser.format_usage().split())[len("usage: ") :]


def _action_row(action: argparse.Action) -> str:
    if action.option_strings:
        name = ", ".join(action.option_strings)
        if action.nargs != 0:
            name += f" {action.metavar or action.dest.upper()}"
    else:
        name = action.metavar or action.dest
    notes = action.help or ("" if action.option_strings else "(positional)")
    if action.required and action.option_strings:
        notes += " (required)"
    return f"| `{name}` | {_cell(notes)} |"


def _subcommands() -> tuple[argparse.ArgumentParser, dict, dict]:
    from coupling.app.cli import build_parser

    parser = build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, subs.choices, {c.dest: c.help for c in subs._choices_actions}


def cli_markdown(command: str = "") -> str:
    """The usage of ``fembem`` and its subcommands (no ``command``), or one subcommand's
    usage, description and arguments, from the parser."""
    parser, subs, helps = _subcommands()
    if not command:
        out = ["```text", _usage(parser), "```", "", _cell(parser.description or ""), ""]
        out += ["| command | what it does |", "|---|---|"]
        out += [f"| `{name}` | {_cell(helps.get(name) or '')} |" for name in subs]
        return "\n".join(out) + "\n"
    sub = subs[command]
    summary = _cell(helps.get(command) or "")
    out = [summary[:1].upper() + summary[1:] + ".", ""]
    if not sub.add_help:  # study, bench: their options are their own scripts'
        return "\n".join(out + [f"Everything after `{command}` is passed on to it."]) + "\n"
    out += ["```text", _usage(sub), "```", ""]
    if sub.description:
        out += [_cell(sub.description), ""]
    actions = [a for a in sub._actions if not isinstance(a, argparse._HelpAction)]
    out += ["| argument | meaning |", "|---|---|"] + [_action_row(a) for a in actions]
    return "\n".join(out) + "\n"


def cli_commands() -> list[str]:
    """The subcommands of ``fembem``, in the parser's order."""
    return list(_subcommands()[1])


def exit_codes_markdown(meanings: Path = EXIT_CODES) -> str:
    """The exit codes of ``fembem``: the values of the ``EXIT_*`` constants of
    ``coupling.app.ending`` (where the CLI takes them from)."""
    from coupling.app import ending

    text = tomllib.loads(meanings.read_text())
    codes: list[tuple[str, int]] = []
    for name in sorted(n for n in vars(ending) if n.startswith("EXIT_")):
        value = getattr(ending, name)
        if isinstance(value, dict):  # signal -> code
            codes += [(f"{name}[{sig.name}]", code) for sig, code in value.items()]
        else:
            codes.append((name, value))
    missing = [n for n, _ in codes if n not in text]
    extra = [n for n in text if n not in dict(codes)]
    if missing or extra:
        raise ValueError(
            f"{meanings}: describe every EXIT_* code of coupling.app.ending "
            f"(missing: {', '.join(missing) or 'none'}; no such code: {', '.join(extra) or 'none'})"
        )
    out = ["| code | constant | meaning |", "|---|---|---|"]
    for name, code in sorted(codes, key=lambda c: c[1]):
        out.append(f"| {code} | `{name}` | {_cell(text[name])} |")
    return "\n".join(out) + "\n"


def error_message(toml_text: str) -> str:
    """The one line ``fembem`` prints for a bad configuration (validated as by
    ``fembem solve``/``info`` before anything is built)."""
    from coupling.app.config import check_data_and_material, parse_config

    try:
        check_data_and_material(parse_config(tomllib.loads(toml_text)))
    except ValueError as err:
        return "fembem: error: " + str(err).splitlines()[0]
    raise ValueError(f"docs/guide/errors.toml: this configuration is valid:\n{toml_text}")


def errors_markdown(cases: Path = ERRORS) -> str:
    """Each case of docs/guide/errors.toml: the configuration, the message, the fix."""
    out: list[str] = []
    for case in tomllib.loads(cases.read_text())["case"]:
        out += [f"**{case['title']}**", "", "```toml", case["config"].strip(), "```", ""]
        out += ["```text", error_message(case["config"]), "```", ""]
        if case.get("fix"):
            out += [case["fix"].strip(), ""]
    return "\n".join(out)
