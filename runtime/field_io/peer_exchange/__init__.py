"""The variable exchange between resources over Zenoh, as a field I/O driver
(docs/exchange.md): publications of chosen globals out, other resources' publications in."""
