from scalesynth.cli import main

main()
