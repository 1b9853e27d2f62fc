from stvm.cli import main

raise SystemExit(main())
