"""Command-line arguments as a user types them, for every ClothLight command.

argparse takes a value that begins with ``-`` (``--dye-series -1,5``, ``--seed -3``) for an option
and refuses it with "expected one argument", which names neither the range nor what was wrong.
:func:`parse_arguments` hands such a value to its option, so that the option's own check refuses
it, naming the parameter and what is allowed, as it refuses every other bad value.
:func:`preset_argument` checks the yarn a command reads under the option the user gave it.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence


def _parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """``parser`` and its sub-commands' parsers (argparse keeps them, and its options, private)."""
    subcommands = [action for action in parser._actions if isinstance(action, argparse._SubParsersAction)]
    return [parser, *(sub for action in subcommands for sub in action.choices.values())]


def values_attached(parser: argparse.ArgumentParser, argv: Sequence[str]) -> list[str]:
    """``argv`` with each value that begins with ``-`` and follows an option taking one value written
    as ``--option=value``; a following word that is itself an option of ``parser`` is left alone."""
    actions = [action for each in _parsers(parser) for action in each._actions if action.option_strings]
    takes_one = {string for action in actions if action.nargs is None for string in action.option_strings}
    options = {string for action in actions for string in action.option_strings}
    attached, words = [], list(argv)
    index = 0
    while index < len(words):
        word = words[index]
        following = words[index + 1] if index + 1 < len(words) else None
        if (word in takes_one and following is not None and following.startswith("-") and following != "--"
                and following.partition("=")[0] not in options):
            attached.append(f"{word}={following}")
            index += 2
        else:
            attached.append(word)
            index += 1
    return attached


def parse_arguments(parser: argparse.ArgumentParser, argv: Sequence[str]) -> argparse.Namespace:
    """``parser.parse_args`` of ``argv`` with its dash-led values attached (:func:`values_attached`)."""
    return parser.parse_args(values_attached(parser, argv))


def preset_argument(args: argparse.Namespace):
    """The yarn a command reads, ``--config FILE`` or else ``--preset NAME`` (the default preset
    when neither is given), checked as a readable preset: ParameterError naming the option as the
    user wrote it, not the API's ``preset``."""
    from precompute.errors import ParameterError
    from precompute.optics.medium import DEFAULT_PRESET, load_preset_config

    option, value = ("--config", args.config) if args.config is not None else ("--preset", args.preset)
    value = DEFAULT_PRESET if value is None else value
    try:
        load_preset_config(value)
    except ParameterError as error:
        if error.name != "preset":
            raise
        raise ParameterError(option, error.value, error.allowed) from None
    return value
