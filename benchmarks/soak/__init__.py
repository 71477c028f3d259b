"""`make soak`: hostile-client and kill -9 scenarios (`python -m benchmarks.soak.run`)."""
