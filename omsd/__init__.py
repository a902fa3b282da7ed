"""omsd: a virtual device server for Oregon Micro Systems motion controllers."""

__version__ = "0.1.0"
