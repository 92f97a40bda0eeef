from dsfd.cli import main

raise SystemExit(main())
