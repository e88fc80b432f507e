"""Readers (video file, image folder, raw stream) -> frames; writers (video, CSV, JSON).

Decoding and encoding run in background threads so the tracker thread does only tracking.
"""

from vtrack.io.csvfile import CsvWriter
from vtrack.io.files import prepare_output_dir
from vtrack.io.inputs import check_input, open_source
from vtrack.io.jsonfile import write_json
from vtrack.io.raw import PIX_FMTS, RawFormat
from vtrack.io.source import InputInfo, Source
from vtrack.io.videowriter import VideoWriter

__all__ = [
    "PIX_FMTS",
    "CsvWriter",
    "InputInfo",
    "RawFormat",
    "Source",
    "VideoWriter",
    "check_input",
    "open_source",
    "prepare_output_dir",
    "write_json",
]
