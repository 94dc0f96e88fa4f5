"""Graphical bodies (FBD and LD): their model, their text form inside an ST file, their
execution order and their lowering to ST statements that the rest of the compiler takes."""
