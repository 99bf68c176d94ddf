"""Episode recordings: :class:`RecordingWriter` writes one, :func:`open_recording` reads one.

The format (a folder of ``.npy`` arrays and a JSON manifest) is documented in
:mod:`pairflock_env.recording.format`.
"""

from pairflock_env.recording.format import (
    FORMAT,
    VERSION,
    Recording,
    RecordingWriter,
    open_recording,
)
from pairflock_env.recording.schema import STEP_ARRAYS

__all__ = ["FORMAT", "STEP_ARRAYS", "VERSION", "Recording", "RecordingWriter", "open_recording"]
