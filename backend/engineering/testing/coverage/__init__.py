"""Statement and branch coverage of the project's POUs by its unit tests (docs/testing.md,
"Coverage"), measured on the Python tier:

- `measure`: which lines of generated code ran, counted while the tests run;
- `model`: those counts as ST statements and branches per file and POU;
- `cobertura`, `html`, `summary`: the model as Cobertura XML, as HTML pages with the
  source shaded, and as a table for the terminal.
"""
