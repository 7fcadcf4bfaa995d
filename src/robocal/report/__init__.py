"""Plots and reports (matplotlib, headless). Imports the library; the library never imports this."""
