"""The code side of the PES: a configuration's generated code made into running objects
(`code_image.py`, `instances.py`, `user_program.py`), what that code may call
(`intrinsics.py`, `printf.py`), a fault traced back to its ST line (`fault_location.py`),
a reload's code compiled in a child process (`compile_worker.py`) and warmed before the
switch-over (`code_warmup.py`), and the native tier that runs bodies as C (`native/`).
docs/native-code.md says where this part is going."""
