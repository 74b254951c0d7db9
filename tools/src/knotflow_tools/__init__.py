"""knotflow_tools: knot, shape and transition analysis of knotflow case files."""

import sys

__version__ = "0.1.0"


def add_version_option(parser):
    """--version on an argparse parser: '<program> <version>' on standard output, exit 0."""
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser


def run_reporting_errors(prog, body, argv=None):
    """body(argv) for a console script: a file that cannot be read or bad input (OSError,
    KeyError, ValueError) is one line '<prog>: error: ...' on standard error, exit status 2."""
    try:
        return body(argv)
    except (OSError, KeyError, ValueError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
