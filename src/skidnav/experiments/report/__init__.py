"""Reading a results directory: statistics, plots, the thesis comparison and the HTML report."""
