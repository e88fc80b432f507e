from vtrack.cli import main

main()
