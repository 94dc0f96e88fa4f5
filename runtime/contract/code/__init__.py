"""The typed form of a program's code: what the compiler makes of every POU as data, from
which the code that runs is made (docs/native-code.md, "The design this tier is moving
to")."""
