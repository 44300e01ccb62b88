;;;; `make bench': load the systems, then every tests/bench/*-bench.lisp, run them, print one table.

(require :asdf)
(defvar *bench-load-start* (get-internal-real-time))
(load (merge-pathnames "bench-lib.lisp" *load-truename*))
(dolist (file (sort (directory (merge-pathnames "*-bench.lisp" *load-truename*))
                    #'string< :key #'namestring))
  (load file))
(cram-bench:run-benchmarks)
(uiop:quit 0)
