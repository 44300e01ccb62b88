;;;; The debugger inside plans: CPL-IMPL:*DEBUG-ON-LISP-ERRORS*, *BREAK-ON-PLAN-FAILURES* and
;;;; CPM:*PROCESS-MODULE-DEBUGGER-HOOK* open it in the task's thread at the failing frame, with
;;;; restarts to continue or to abort the plan; the log follows the caller's output.

(in-package :cram-plans-tests-repl)

(in-suite repl)

(defun failing-plan-step (x)
  "A plan step with a Lisp error in it (X is not a number)."
  (declare (notinline +) (optimize (debug 2)))   ; keeps this frame (no tail call)
  (list (+ x 1)))

(defun sb-debug-list-backtrace-frames ()
  "The names of the functions on the current thread's stack, innermost first."
  (mapcar (lambda (frame) (if (consp frame) (first frame) frame)) (sb-debug:list-backtrace)))

(defun frame-names (names) names)

(test debug-on-lisp-errors-opens-the-debugger-at-the-failing-frame
  (let ((condition nil) (frames nil) (thread nil) (thread-name nil) (caller (bt:current-thread)))
    (let ((cpl-impl:*debug-on-lisp-errors* t)
          (sb-ext:*invoke-debugger-hook* nil) ; this image may run with --disable-debugger
          (*debugger-hook* (lambda (c hook)
                             (declare (ignore hook))
                             (setf condition c
                                   thread (bt:current-thread)
                                   thread-name (bt:thread-name thread)
                                   frames (frame-names (sb-debug-list-backtrace-frames)))
                             (invoke-restart 'continue))))
      ;; CONTINUE: the error ends the task as a plan failure, which failure handling sees
      (is (eq :handled
              (cpl:top-level
                (cpl:with-failure-handling
                    ((cpl:common-lisp-error-envelope (e) (declare (ignore e)) (return :handled)))
                  (cpl:par (failing-plan-step "one") (cpl:sleep 0.01)))))))
    (is (typep condition 'type-error))
    (is (not (eq thread caller)) "the debugger did not open in the task's thread")
    (is (uiop:string-prefix-p "cpl " thread-name))
    (is (member 'failing-plan-step frames) "the failing frame is not in the backtrace: ~s"
        (subseq frames 0 (min 15 (length frames))))))

(test debug-on-lisp-errors-abort-plan
  (let ((cpl:*debug-on-lisp-errors* t)
        (sb-ext:*invoke-debugger-hook* nil) ; this image may run with --disable-debugger
          (*debugger-hook* (lambda (c hook) (declare (ignore hook)) (cpl:abort-plan c))))
    (signals cpl:plan-aborted
      (cpl:top-level (cpl:par (failing-plan-step :two) (cpl:sleep 5))))
    ;; nothing of the plan is left running
    (is (notany (lambda (th) (uiop:string-prefix-p "cpl " (bt:thread-name th)))
                (bt:all-threads)))))

(test debug-on-lisp-errors-off-by-default
  (is (null cpl-impl:*debug-on-lisp-errors*))
  (let ((entered nil))
    (let ((sb-ext:*invoke-debugger-hook* nil) ; this image may run with --disable-debugger
          (*debugger-hook* (lambda (c hook) (declare (ignore c hook)) (setf entered t) (abort))))
      (signals type-error (cpl:top-level (failing-plan-step "x"))))
    (is (not entered))))

(test break-on-plan-failures
  (let ((seen '()))
    (let ((cpl-impl:*break-on-plan-failures* 'common-fail:perception-object-not-found)
          (sb-ext:*invoke-debugger-hook* nil) ; this image may run with --disable-debugger
          (*debugger-hook* (lambda (c hook)
                             (declare (ignore hook))
                             (push (type-of c) seen)
                             (invoke-restart 'continue))))
      (is (eq :caught
              (cpl:top-level
                (cpl:with-failure-handling
                    ((cpl:plan-failure (e) (declare (ignore e)) (return :caught)))
                  (cpl:fail 'common-fail:perception-object-not-found :description "no bottle")))))
      ;; a failure of another type does not stop
      (cpl:top-level
        (cpl:with-failure-handling ((cpl:plan-failure (e) (declare (ignore e)) (return nil)))
          (cpl:fail "simple"))))
    (is (equal '(common-fail:perception-object-not-found) seen))
    (let ((cpl:*break-on-plan-failures* '(not-a-type 1 2)))
      (signals error (cpl:top-level (cpl:fail "x"))))))

(cpm:def-process-module repl-test-pm (designator)
  (failing-plan-step designator))

(test process-module-debugger-hook
  (let ((seen nil) (frames nil))
    (let ((sb-ext:*invoke-debugger-hook* nil)
          (cpm:*process-module-debugger-hook*
            (lambda (c hook)
              (declare (ignore hook))
              (setf seen c frames (frame-names (sb-debug-list-backtrace-frames)))
              (cpm:continue-pm c))))
      (signals type-error
        (cpl:top-level
          (cpm:with-process-modules-running (repl-test-pm)
            (cpm:pm-execute 'repl-test-pm "not a number")))))
    (is (typep seen 'type-error))
    (is (member 'failing-plan-step frames)))
  (let ((cpm:*process-module-debugger-hook* 42))
    (signals error (cpl:top-level (cpm:with-process-modules-running (repl-test-pm)
                                    (cpm:pm-execute 'repl-test-pm 1)))))
  (signals error (cpm:continue-pm))
  (signals error (cpl:abort-plan)))

(test cpl-impl-is-crams-implementation-package
  (is (string= "CRAM-LANGUAGE-IMPLEMENTATION" (package-name (find-package :cpl-impl))))
  (is (eq 'cpl-impl:*debug-on-lisp-errors* 'cpl:*debug-on-lisp-errors*))
  (is (eq 'cpl-impl:top-level 'cpl:top-level))
  (is (eq 'cpl-impl:with-failure-handling 'cpl:with-failure-handling))
  (is (eq 'cpl-impl:fl-and 'cpl:fl-and))
  (do-external-symbols (symbol :cpl-impl)
    (is (eq :external (nth-value 1 (find-symbol (symbol-name symbol) :cpl))))))

(test cpl-impl-loads-again-without-warnings
  ;; as loading the file just compiled does: the package is made once, its exports kept
  (let ((warnings '())
        (count (let ((n 0)) (do-external-symbols (s :cpl-impl) (declare (ignore s)) (incf n)) n)))
    (handler-bind ((warning (lambda (w) (push w warnings) (muffle-warning w))))
      (load (asdf:system-relative-pathname "cram-plans" "src/language/implementation-package.lisp")))
    (is (null warnings) "~{~a~^; ~}" warnings)
    (is (eq 'cpl-impl:fail 'cpl:fail))
    (is (= count (let ((n 0)) (do-external-symbols (s :cpl-impl) (declare (ignore s)) (incf n)) n)))))

(test log-lines-go-to-the-callers-output
  (is (null cpl:*log-stream*))
  (flet ((run-plan ()
           (with-output-to-string (*standard-output*)
             (cpl:top-level (cpl:par (cpl:log-info "from a child task") (cpl:log-info "another"))))))
    (let ((first (run-plan)) (second (run-plan)))
      (is (= 2 (count-lines-with first "from a child task" "another")))
      (is (= 2 (count-lines-with second "from a child task" "another")))))
  (let ((cpl:*log-stream* 17))
    (signals error (cpl:log-info "x"))))

(defun count-lines-with (text &rest needles)
  (count-if (lambda (line) (some (lambda (needle) (search needle line)) needles))
            (uiop:split-string text :separator '(#\Newline))))
