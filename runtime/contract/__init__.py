"""The contract of the PES: what a resource accepts and what it speaks, and nothing else.

The compiled artifact and its version (`artifact`), the value representation (`values`),
the parameter table (`parameters`), the system variables (`system_variables`), accounts and
access levels (`accounts`), the Zenoh key space (`keyspace`) and how a session is opened
(`session`, `session_options`), and the bus protocol: one typed message per command and
publication (`protocol`), checked by one decoder (`wire`). The compiler, the engineering
services, the REST API, the UI and the command line import only this package of the
runtime; this package imports nothing else of the project (import-linter checks both).
"""
