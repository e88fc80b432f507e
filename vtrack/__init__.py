"""vtrack: classic real-time video object tracking (library and ``vtrack`` command)."""

__version__ = "0.1.0"
