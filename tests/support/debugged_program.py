"""The program the debugging tests stop, step and look into (runtime, `padt dap`): an FB
called by two instances, one of them through an interface's method, a FUNCTION, a FOR
loop, and a second program that must run on while the first stands at a breakpoint. Tests
name its lines by number: change it and they change."""

COUNTERS = """\
INTERFACE ICount
  METHOD Bump : INT
  VAR_INPUT by : INT; END_VAR
  END_METHOD
END_INTERFACE

FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
VAR tmp : INT; END_VAR
tmp := x * 2;
Twice := tmp;
END_FUNCTION

FUNCTION_BLOCK Counter IMPLEMENTS ICount
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT total : INT; END_VAR
total := total + step;
total := Twice(total) / 2;
METHOD PUBLIC Bump : INT
VAR_INPUT by : INT; END_VAR
total := total + by;
Bump := total;
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR a, b : Counter; i : INT; n : INT; c : ICount; END_VAR
a(step := 1);
b(step := 2);
c := a;
n := c.Bump(by := 3);
FOR i := 1 TO 3 DO
  n := n + i;
END_FOR;
END_PROGRAM

PROGRAM Other
VAR ticks : DINT; END_VAR
ticks := ticks + 1;
END_PROGRAM
"""
