"""The code editor in the centre of the browser: CodeMirror (bundled from
scripts/codemirror/) over viser's canvas, and its bridge to the server (`editor_area`)."""
