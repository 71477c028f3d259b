"""Speed and soak measurements (`make bench`, `make soak`); not tests. A package, as `tests` is,
so benchmarks import the tests' helpers (`tests.apps.acomms_mission`, `tests.faults`, ...) from
the repository root."""
