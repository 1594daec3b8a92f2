"""The ``shrm`` command line: thin wrappers that parse, call the public API and format."""
