"""Benchmarks behind ``dsfd bench TARGET``: each returns flat figures with units in the keys.

Speed, memory and accuracy targets live here, never in the tests (which check behaviour).
"""
