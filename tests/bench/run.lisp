;;;; `make bench': load every tests/bench/*-bench.lisp (each loads the systems it measures),
;;;; run the benchmarks and print one table. plans-soak-bench.lisp is the memory soak, a
;;;; 20 000-run campaign (CRAM_SOAK_RUNS=N for another size, 0 to skip it).

(require :asdf)
(handler-bind ((warning #'muffle-warning))
  (asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*)))
(load (merge-pathnames "bench-lib.lisp" *load-truename*))
(dolist (file (sort (directory (merge-pathnames "*-bench.lisp" *load-truename*))
                    #'string< :key #'namestring))
  (handler-bind ((warning #'muffle-warning))
    (load file)))
(cram-bench:run-benchmarks)
(uiop:quit 0)
