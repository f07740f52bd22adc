"""The worker's tests use the app in-process (`tests.unit.server.conftest`)."""

from tests.unit.server.conftest import client, prepared

__all__ = ["client", "prepared"]
