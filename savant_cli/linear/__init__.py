"""savant_cli.linear"""
