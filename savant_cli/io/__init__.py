"""savant_cli.io"""
