"""``python -m scalesynth``: the same CLI as the ``scalesynth`` command. Importing this module runs nothing."""

if __name__ == "__main__":
    from scalesynth.cli import main

    main()
