"""knotflow_tools: knot, shape and transition analysis of knotflow case files."""

__version__ = "0.1.0"


def add_version_option(parser):
    """--version on an argparse parser: '<program> <version>' on standard output, exit 0."""
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser
