"""What a run left in an output folder."""

import subprocess
import sys
from pathlib import Path


def produced_names(folder) -> list[str]:
    """Names in ``folder`` except the manifest and lock hht3d keeps in every local output folder (temporaries stay)."""
    from hht3d.io.lock import LOCK
    from hht3d.io.manifest import MANIFEST

    return sorted(p.name for p in Path(folder).iterdir() if p.name not in (MANIFEST, LOCK))


def dead_writers_part(folder, name: str) -> Path:
    """The temporary file a worker killed mid-write leaves (``.NAME.PID-XXXXXXXX.part``, its
    process gone), made in ``folder``."""
    ended = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True, check=True
    )
    part = Path(folder) / f".{name}.{int(ended.stdout)}-abcd1234.part"
    part.parent.mkdir(parents=True, exist_ok=True)
    part.write_bytes(b"half an output")
    return part
