from vissim.cli import run

run()
