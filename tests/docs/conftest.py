"""The documentation runs' fork server stops with the test session (``fork_server``), so that
its CPU time is counted in the session's (a pytest-xdist worker may end without exit
handlers)."""

import pytest


@pytest.fixture(scope="session", autouse=True)
def _stop_the_fork_server():
    yield
    from .test_docs_run import _SERVER

    for server in _SERVER:
        server.close()
