"""Imported first, makes grpc and google.protobuf unimportable in this
interpreter, as when the package is installed without its extra
geodex[client] on a machine without them. test_without_client.py imports it
in a child interpreter; the wheel test installs it into a virtual
environment of its own with a .pth file
(tests/integration/python_wheel_test.sh)."""

from __future__ import annotations

import importlib.abc
import sys
from typing import Any, Optional

HIDDEN = ("grpc", "grpc_tools", "google.protobuf")


class _Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Optional[Any]:
        if any(name == h or name.startswith(h + ".") for h in HIDDEN):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


if not any(isinstance(f, _Hide) for f in sys.meta_path):
    sys.meta_path.insert(0, _Hide())
