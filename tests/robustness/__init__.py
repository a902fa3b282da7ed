"""Robustness tests (issue 7): fuzz, churn, floods and slow readers, signals, isolation.

The default pass is short (a few seconds per test); ``pytest tests/robustness --long`` or
``OMSD_LONG=1`` runs the long variants (10^6 fuzz inputs, 1,000 TCP churn cycles, ...).
"""
