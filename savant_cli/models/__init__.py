"""savant_cli.models"""
