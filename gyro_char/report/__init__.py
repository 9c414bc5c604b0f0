"""Plots (rendered to files with the Agg backend) and human tables, one module per result."""
