"""What a run left in an output folder."""
from pathlib import Path


def produced_names(folder) -> list[str]:
    """Names in ``folder`` except the manifest and lock hht3d keeps in every local output folder (temporaries stay)."""
    from hht3d.io.manifest import LOCK, MANIFEST

    return sorted(p.name for p in Path(folder).iterdir() if p.name not in (MANIFEST, LOCK))
