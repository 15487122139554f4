"""savant_cli.plots"""
