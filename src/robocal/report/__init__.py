"""Plots and reports: SVG charts written as text (svg, _figures, the HTML report) and headless matplotlib
for PNG files (plots, history_plot). Imports the library; the library never imports this."""
