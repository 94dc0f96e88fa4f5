"""Test oracles: independent, deliberately simple executions of ST to check the compiler by."""
