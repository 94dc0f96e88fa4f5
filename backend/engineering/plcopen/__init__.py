"""PLCopen TC6 XML import: the XML read safely into a small tree (`xml_tree`), the tree into
dataclasses (`model`, `reader`), an SFC network into textual SFC (`sfc`), the model into ST
text (`st_text`) and the project files (`project_files`); `importer` is the service that
`padt import` calls. docs/plcopen-import.md describes what is imported and how."""
