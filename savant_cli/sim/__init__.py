"""savant_cli.sim"""
