"""The PADT's REST API (FastAPI): every engineering operation over HTTP, for CI pipelines,
scripts and third-party tools. docs/rest-api.md is its reference; OpenAPI at /docs."""
