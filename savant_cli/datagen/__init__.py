"""savant_cli.datagen"""
