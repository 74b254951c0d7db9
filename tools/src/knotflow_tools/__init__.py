"""knotflow_tools: knot, shape and transition analysis of knotflow case files.

The modules are libraries; the console scripts are in `cli`."""

__version__ = "0.1.0"
