"""The PADT: the compiler (`compiler`), the engineering services (`engineering`) and the
REST API over them (`api`)."""
