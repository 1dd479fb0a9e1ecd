"""The figures (PNG and the Vega-Lite specs the pages embed), and the scaling and workload outputs that draw them."""
