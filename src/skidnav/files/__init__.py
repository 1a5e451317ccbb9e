"""Files: atomic writes, saved files, user files, JSON depth, config tables, output folders."""
