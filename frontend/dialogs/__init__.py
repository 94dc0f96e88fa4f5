"""Dialogs that act on a resource from anywhere in the workspace (the editor's toolbar, a
screen of the work area): Compile, Download, Online change. Each is a plain function over
what it needs of the browser (`Deployment`); the work is the engineering services'."""
