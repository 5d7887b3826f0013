"""Shared pytest options: ``--runslow`` enables studies marked ``slow``. NGFRAC_THREADS, when
set, caps NGSolve's threads for the whole session (importing ngfrac does not).

tests/ is a package (tests/__init__.py), so pytest puts the checkout on sys.path, not tests/:
with tests/ there, the folders tests/ngfrac (since moved) and tests/estimators shadowed the ngfrac and
estimators packages as namespace packages (``pytest`` run from an installed entry point then
imported the installed checkout's ngfrac, whatever the working tree). Shared scenes are in
:mod:`ngfrac.testing`."""
import pytest


def pytest_addoption(parser):
    parser.addoption("--runslow", action="store_true", default=False,
                     help="also run tests marked slow (long convergence studies)")


def pytest_sessionstart(session):
    import ngfrac

    ngfrac.set_threads()


@pytest.fixture(scope="module")
def one_thread():
    """One NGSolve thread for a module (its worker threads busy-wait: one is faster on a
    shared machine), then the configured count again (NGFRAC_THREADS)."""
    from ngfrac.fem.threads import single_thread

    with single_thread():
        yield


def pytest_collection_modifyitems(config, items):
    if config.getoption("--runslow"):
        return
    skip_slow = pytest.mark.skip(reason="slow study: run with --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip_slow)
