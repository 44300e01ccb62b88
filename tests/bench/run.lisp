;;;; `make bench': load every tests/bench/*-bench.lisp (each loads the systems it measures),
;;;; run the benchmarks and print one table.

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
