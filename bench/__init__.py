"""Benchmarks that print figures (run from the root of the source tree, ``make bench``);
:mod:`bench.peers` is the peer benchmark, the other modules are scripts."""
