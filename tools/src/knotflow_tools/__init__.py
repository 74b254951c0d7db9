"""knotflow_tools: knot, shape and transition analysis of knotflow case files."""

__version__ = "0.1.0"
