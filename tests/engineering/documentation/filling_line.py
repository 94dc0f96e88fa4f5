"""A small project with everything a document shows: globals and I/O with comments, a
structure and an enumeration, an SFC program, a function with an in-out, two programs,
users and a safe value."""

from __future__ import annotations

from pathlib import Path

from runtime.contract.accounts import hash_password

PADT_TOML = """\
[project]
name = "Filling line"
version = "2.1"
author = "A. Engineer"
date = "2026-11-20"

[resource]
name = "Line1"
target_cycle_ms = 50
watchdog_ms = 150

[resource.safe_values]
conveyor_run = false

[[resource.program]]
name = "Filler"
pou = "Filler"
id = 1

[[resource.program]]
name = "Conveyor"
pou = "Conveyor"
id = 2
priority = 1

[[resource.user]]
name = "admin"
level = "administrator"
password_hash = "ADMIN_HASH"

[[resource.user]]
name = "op"
level = "operator"
password_hash = "OP_HASH"
"""

GLOBALS_ST = """\
TYPE Recipe : STRUCT
  volume : INT := 500;   (* millilitres per bottle *)
  dwell : TIME := T#2s;  (* settling time *)
END_STRUCT; END_TYPE
TYPE Mode : (Idle, Running, Fault); END_TYPE

VAR_GLOBAL
  start_button AT %IX0.0 : BOOL;    (* operator start, NO contact *)
  bottle_present AT %IX0.1 : BOOL;  (* light barrier at the filler *)
  valve_open AT %QX0.0 : BOOL;      (* filling valve *)
  conveyor_run AT %QX0.1 : BOOL;    (* conveyor motor *)
  bottles : DINT;                   (* bottles filled since the cold start *)
  recipe : Recipe;                  (* the product being filled *)
END_VAR
"""

FILLER_ST = """\
PROGRAM Filler
VAR_EXTERNAL
  start_button : BOOL;
  bottle_present : BOOL;
  valve_open : BOOL;
  bottles : DINT;
  recipe : Recipe;
END_VAR
VAR
  fill_timer : TON;  (* how long the valve stays open *)
END_VAR
INITIAL_STEP Wait: CloseValve(N); END_STEP
TRANSITION FROM Wait TO Fill := start_button AND bottle_present; END_TRANSITION
STEP Fill: OpenValve(N); Count(P); END_STEP
TRANSITION FROM Fill TO Settle := fill_timer.Q; END_TRANSITION
STEP Settle: CloseValve(N); END_STEP
TRANSITION FROM Settle TO Wait := NOT bottle_present; END_TRANSITION
ACTION OpenValve:
  valve_open := TRUE;
  fill_timer(IN := Fill.X, PT := recipe.dwell);
END_ACTION
ACTION CloseValve:
  valve_open := FALSE;
END_ACTION
ACTION Count:
  bottles := bottles + 1;
END_ACTION
END_PROGRAM
"""

CONVEYOR_ST = """\
FUNCTION Limit100 : INT
VAR_INPUT
  x : INT;  (* requested speed *)
END_VAR
VAR_IN_OUT
  clipped : BOOL;  (* set when x was out of range *)
END_VAR
clipped := x > 100;
IF clipped THEN
  Limit100 := 100;
ELSE
  Limit100 := x;
END_IF;
END_FUNCTION

PROGRAM Conveyor
VAR_EXTERNAL
  bottle_present : BOOL;
  conveyor_run : BOOL;
END_VAR
VAR
  speed : INT := 40;  (* percent of the motor's rated speed *)
  clipped : BOOL;
END_VAR
conveyor_run := NOT bottle_present;
speed := Limit100(x := speed + 5, clipped := clipped);
END_PROGRAM
"""


def write_filling_line(folder: Path) -> Path:
    """The project in `folder` (created); the users' hashes with fixed salts, so the
    project is the same bytes every time."""
    folder.mkdir(parents=True, exist_ok=True)
    config = PADT_TOML.replace("ADMIN_HASH", hash_password("admin-pw", b"0" * 16)).replace(
        "OP_HASH", hash_password("op-pw", b"1" * 16)
    )
    (folder / "padt.toml").write_text(config)
    (folder / "globals.st").write_text(GLOBALS_ST)
    (folder / "filler.st").write_text(FILLER_ST)
    (folder / "conveyor.st").write_text(CONVEYOR_ST)
    return folder
