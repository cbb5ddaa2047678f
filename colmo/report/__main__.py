"""`python -m colmo.report`: the same as `colmo-report`."""

from colmo.report import main

main()
