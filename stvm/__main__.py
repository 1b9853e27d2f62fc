import sys

try:
    from stvm.cli import program
except KeyboardInterrupt:  # Ctrl-C while Python imports stvm itself
    print("stvm: interrupted", file=sys.stderr)
    raise SystemExit(130)

raise SystemExit(program())
