"""The engineering services: one module per job (project, compile-twice gate, download,
reload, backup, simulation, the session with a resource, the resources online). The REST
API, the browser UI and the command line are thin adapters over these."""
