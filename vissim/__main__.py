import sys

from vissim.cli import main

sys.exit(main())
