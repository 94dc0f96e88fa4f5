"""`padt test`: unit tests written in ST, run on virtual time on both tiers (docs/testing.md).

- `test_build`: the project with its test files (and libraries) compiled, and the tests found;
- `test_run`: the tests of a build run on one tier, cycle by cycle;
- `tiers`: both tiers, compared after every cycle;
- `results` and `junit`: what a run found, for a terminal and for CI.
"""
