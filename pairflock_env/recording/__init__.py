"""Episode recordings: :class:`RecordingWriter` writes one, :func:`open_recording` reads one,
:class:`CoreRecorder` / :func:`record_core` record every episode a core runs (one recording
per swarm and episode; :class:`~pairflock_env.envs.record.RecordEpisode` wraps a view).

The format (a folder of ``.npy`` arrays and a JSON manifest) is documented in
:mod:`pairflock_env.recording.format`.
"""

from pairflock_env.recording.episodes import CoreRecorder, record_core
from pairflock_env.recording.format import (
    FORMAT,
    VERSION,
    Recording,
    RecordingWriter,
    open_recording,
)
from pairflock_env.recording.schema import STEP_ARRAYS

__all__ = [
    "FORMAT",
    "STEP_ARRAYS",
    "VERSION",
    "CoreRecorder",
    "Recording",
    "RecordingWriter",
    "open_recording",
    "record_core",
]
