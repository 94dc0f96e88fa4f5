"""The PADT services: project model, compiler, link client and (later) reload, docs, API."""
