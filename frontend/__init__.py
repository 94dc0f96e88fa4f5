"""The browser UI, built with viser; it talks to resources only through the backend."""
