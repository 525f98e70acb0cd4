"""What a report says about the machine it was measured on."""

from __future__ import annotations

import os
import platform
from pathlib import Path


def machine() -> dict:
    """CPU count, model and clock (the first `cpu MHz`, None when unknown), memory, load
    average, kernel, Python and numpy versions."""
    import numpy as np

    model, mhz, mem_kib = "?", None, None
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name") and model == "?":
                model = line.split(":", 1)[1].strip()
            if line.startswith("cpu MHz") and mhz is None:
                mhz = float(line.split(":", 1)[1])
        mem_kib = int(Path("/proc/meminfo").read_text().splitlines()[0].split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return {
        "nproc": os.cpu_count(),
        "cpu": model,
        "mhz": mhz,
        "memory_gib": round(mem_kib / 2**20, 1) if mem_kib else None,
        "loadavg": os.getloadavg() if hasattr(os, "getloadavg") else None,
        "kernel": platform.release(),
        "python": platform.python_version(),
        "numpy": np.__version__,
    }
