;;;; The seeds' own pages replayed as tests: each tests/seeds/seed-NNN.lisp runs in a fresh SBCL
;;;; that loads cram-plans the way the README tells a user (the checkout on ASDF's central
;;;; registry, no CL_SOURCE_REGISTRY), reads ../shared/seeds/NNN_*.txt and pastes its code blocks.

(defpackage :cram-seeds-tests
  (:use :cl :fiveam)
  (:export #:run-seed))

(in-package :cram-seeds-tests)

(def-suite seeds :in cram-plans-tests:all
  :description "Seed replays: every code block of every tutorial page, as its reader pastes it.")
(in-suite seeds)

(defun seed-directory () (asdf:system-relative-pathname "cram-plans/tests/base" "tests/seeds/"))

(defvar *seed-log-directory*
  (merge-pathnames "cram-plans-seed-logs/" (uiop:temporary-directory))
  "Where the seed replays' logs go: one temporary folder whose logs each run replaces (the
checkout's out/ belongs to the user).")

(defun run-seed (number)
  "Replay seed NUMBER in a fresh SBCL. Returns its exit code, its `seed NNN: K/N blocks' line
and its whole output; the output is also kept in *SEED-LOG-DIRECTORY*'s seed-NUMBER.log."
  (let* ((env (remove-if (lambda (kv) (or (uiop:string-prefix-p "CL_SOURCE_REGISTRY=" kv)
                                          (uiop:string-prefix-p "ROS_MASTER_URI=" kv)))
                         (sb-ext:posix-environ)))
         (log (merge-pathnames (format nil "seed-~a.log" number) *seed-log-directory*))
         (process (sb-ext:run-program "/usr/bin/env"
                                      (list "sbcl" "--noinform" "--non-interactive" "--no-userinit"
                                            "--no-sysinit"
                                            "--load" (namestring (merge-pathnames "run-seed.lisp" (seed-directory)))
                                            "--eval" (format nil "(seed-run ~s)" number))
                                      :environment env :output :stream :error :output :input nil
                                      :wait nil :directory (namestring (seed-directory))))
         (out (with-output-to-string (s)
                (loop for line = (read-line (sb-ext:process-output process) nil)
                      while line do (write-line line s)))))
    (sb-ext:process-wait process)
    (ensure-directories-exist log)
    (with-open-file (f log :direction :output :if-exists :supersede) (write-string out f))
    (let ((line (find-if (lambda (l) (uiop:string-prefix-p "seed " l))
                         (reverse (uiop:split-string out :separator '(#\Newline))))))
      (format t "~&~a~%" (or line (format nil "seed ~a: no verdict (see ~a)" number log)))
      (finish-output)
      (values (sb-ext:process-exit-code process) line out))))

(defun seed-numbers ()
  (sort (remove-if-not (lambda (n) (and (= (length n) 3) (every #'digit-char-p n)))
                       (mapcar (lambda (p) (subseq (pathname-name p) 5))
                               (directory (merge-pathnames "seed-*.lisp" (seed-directory)))))
        #'string<))

(defparameter *known-short*
  '()
  "Seeds that do not replay completely yet: (NUMBER MINIMUM REASON). The replay must still
reach MINIMUM blocks (a ratchet against regressions) while its line shows the honest K/N.
An entry is removed once its seed replays N/N.")

(defun verdict-counts (line)
  "K and N of a `seed NNN: K/N blocks' LINE, or NIL."
  (let* ((colon (and line (search ": " line)))
         (slash (and colon (position #\/ line :start colon))))
    (when slash
      (values (parse-integer line :start (+ colon 2) :end slash :junk-allowed t)
              (parse-integer line :start (1+ slash) :junk-allowed t)))))

(test seed-replays
  "Every seed page replays completely (K = N blocks), or, for a seed listed in *KNOWN-SHORT*, at
least its recorded minimum."
  (dolist (n (seed-numbers))
    (multiple-value-bind (code line out) (run-seed n)
      (let ((short (assoc n *known-short* :test #'string=))
            (fails (let ((f (remove-if-not (lambda (l) (search ";; FAIL" l))
                                           (uiop:split-string out :separator '(#\Newline)))))
                     (format nil "~{~a~%~}" (subseq f 0 (min 20 (length f)))))))
        (if (and short (not (eql 0 code)))
            (let ((k (verdict-counts line)))
              (format t "~&;; seed ~a is known to be short (~a): at least ~d blocks required~%"
                      n (third short) (second short))
              (is (and k (>= k (second short)))
                  "seed ~a: ~a, below its recorded minimum ~d~%~a" n (or line "no verdict")
                  (second short) fails))
            (is (eql 0 code) "seed ~a: ~a~%~a" n (or line "no verdict") fails))))))
