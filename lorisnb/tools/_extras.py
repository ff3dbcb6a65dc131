"""Optional dependencies: imported when first needed, with an error naming the extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

from lorisnb.errors import MissingDependencyError

#: Which extra of lorisnb brings which top-level package.
EXTRAS: dict[str, str] = {
    "evo": "evo",
    "papermill": "notebooks",
    "nbformat": "notebooks",
    "nbconvert": "notebooks",
    "ipywidgets": "notebooks",
    "IPython": "notebooks",
    "dask": "dask",
    "distributed": "dask",
    "pyarrow": "parquet",
    "rosbags": "bags",
    "fastapi": "serve",
    "starlette": "serve",
    "uvicorn": "serve",
    "sqlalchemy": "serve",
    "multipart": "serve",
    "httpx": "serve",
}


def require(module: str, extra: str | None = None) -> ModuleType:
    """Import ``module``; if it is missing, raise MissingDependencyError naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        top = module.split(".")[0]
        name = extra or EXTRAS.get(top, "all")
        raise MissingDependencyError(
            f"this part of lorisnb needs the package {top!r}, which is not installed ({exc}); "
            f"install it with: pip install 'lorisnb[{name}]'"
        ) from None
