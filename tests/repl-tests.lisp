;;;; A user's day at the REPL: a swank server (Debian's cl-swank) with a client speaking SLIME's
;;;; protocol runs the README's forms, sees the log lines on its connection, reconnects and still
;;;; sees them, and interrupts a long loop of plans; loading what is loaded loads nothing and
;;;; prints nothing, and nothing a user set is reset.

(in-package :cram-plans-tests-repl)

(def-suite repl :in cram-plans-tests:all
  :description "A user's day at the REPL: swank, reloads, the debugger inside plans, logging.")

(in-suite repl)

(defparameter *file-counter-form*
  "(progn
     (defvar cl-user::*files-loaded* 0)
     (defmethod asdf:perform :before ((o asdf:load-op) (c asdf:cl-source-file))
       (incf cl-user::*files-loaded*))
     (defun cl-user::files-loaded-by (thunk)
       (setf cl-user::*files-loaded* 0)
       (funcall thunk)
       cl-user::*files-loaded*))"
  "Counts the Lisp files ASDF loads, typed into the server's REPL.")

(defun log-lines (text)
  "The lines of TEXT in the shape of CPL's log lines."
  (remove-if-not (lambda (line) (and (uiop:string-prefix-p "[(" line) (search " INFO] " line)))
                 (uiop:split-string text :separator '(#\Newline))))

(defun value-line (output)
  "The last non-empty line of OUTPUT: the printed value of a REPL evaluation."
  (let ((lines (remove "" (mapcar (lambda (line) (string-trim '(#\Space #\Return) line))
                                  (uiop:split-string output :separator '(#\Newline)))
                       :test #'string=)))
    (car (last lines))))

(defun ok-output (result)
  "The output of a REPL-EVAL result that must have succeeded."
  (unless (wire-symbol-p (first result) "OK")
    (error "The REPL evaluation did not return normally: ~s~%~a" (first result) (second result)))
  (second result))

(test swank-day-at-the-repl
  "Load, the README's forms, log lines on the connection, reconnect, interrupt a long loop."
  (let ((server (start-swank-server)) (first-connection nil) (second-connection nil))
    (unwind-protect
         (let ((connection (setf first-connection (connect-swank server))))
           ;; the README's REPL block, form by form
           (ok-output (repl-eval connection "(require :asdf)"))
           (ok-output (repl-eval connection "(push (uiop:getcwd) asdf:*central-registry*)"))
           (ok-output (repl-eval connection "(asdf:load-system \"cram-plans\")"))
           (ok-output (repl-eval connection *file-counter-form*))
           ;; loading what is loaded loads nothing and prints nothing
           (let ((output (ok-output (repl-eval connection "(cl-user::files-loaded-by (lambda () (asdf:load-system \"cram-plans\")))"))))
             (is (equal "0" (value-line output)) "a second load-system loaded files: ~a" output)
             (is (not (search "WARNING" output)) "a second load-system printed warnings: ~a" output))
           (ok-output (repl-eval connection "(in-package :btw-tut)"))
           ;; a user's setting, then init-projection: no file loaded, no warning, setting kept
           (ok-output (repl-eval connection "(setf urdf-proj::*ik-max-iterations* 77)"))
           (let ((output (ok-output (repl-eval connection "(cl-user::files-loaded-by #'init-projection)"))))
             (is (equal "0" (value-line output)) "init-projection loaded files: ~a" output)
             (is (search "http://127.0.0.1:" output) "init-projection did not print the viewer's URL: ~a" output)
             (is (not (search "WARNING" output)) "init-projection printed warnings: ~a" output))
           (let ((output (ok-output (repl-eval connection "(move-bottle)"))))
             (is (> (length (log-lines output)) 20)
                 "move-bottle's log lines did not reach the connection: ~a" (subseq output 0 (min 2000 (length output)))))
           (let ((output (ok-output (repl-eval connection "urdf-proj::*ik-max-iterations*"))))
             (is (equal "77" (value-line output)) "the user's setting was reset: ~a" output))
           ;; the tools of SLIME: completion, arglists, documentation
           (is (search "with-failure-handling"
                       (format nil "~(~s~)" (rex connection "(swank:simple-completions \"cpl:with-failure-han\" \"COMMON-LISP-USER\")"))))
           (is (search "clauses"
                       (format nil "~(~s~)" (rex connection "(swank:operator-arglist \"with-failure-handling\" \"CPL\")"))))
           (is (search "debugger"
                       (format nil "~(~s~)" (rex connection "(swank:documentation-symbol \"cpl-impl:*debug-on-lisp-errors*\")"))))
           ;; disconnect, connect again: the log lines come to the new connection
           (disconnect-swank connection)
           (setf first-connection nil)
           (setf connection (setf second-connection (connect-swank server)))
           (let ((output (ok-output (repl-eval connection "(btw-tut:move-bottle)"))))
             (is (> (length (log-lines output)) 20)
                 "after a reconnect, move-bottle's log lines did not reach the new connection: ~a"
                 (subseq output 0 (min 2000 (length output)))))
           ;; a long loop of plans logging at the default level, read by a client that takes
           ;; 2 ms per output message (Emacs inserting it): the interrupt opens the debugger at once
           (setf (conn-message-delay connection) 0.002)
           (let ((id (send-rex connection
                               (format nil "(swank-repl:listener-eval ~s)"
                                       (format nil "(loop repeat 3000 do (btw-tut:move-bottle))~%"))
                               :package (conn-package connection) :thread :repl-thread)))
             (pump connection (constantly nil) 4)
             (is (> (length (log-lines (take-output connection))) 50) "the loop logs")
             ;; C-c, then q in the debugger. An interrupt that lands while SWANK itself waits
             ;; for Emacs to take the output (its flow control) can come back to the loop when
             ;; the debugger is quit, as in Emacs; the user presses C-c and q again: up to three
             ;; times here, each debugger opening at once, and the loop must end aborted.
             (let ((return nil))
               (loop repeat 3
                     until return
                     do (let* ((start (get-internal-real-time))
                               (debug (progn (send-message connection "(:emacs-interrupt :repl-thread)")
                                             (pump connection #'debug-message-p 60)))
                               (seconds (/ (- (get-internal-real-time) start)
                                           internal-time-units-per-second)))
                          (is (not (null debug)) "no debugger after the interrupt")
                          (is (< seconds 1.5) "the interrupt took ~,2f s to open the debugger"
                              (float seconds))
                          (unless debug (return))
                          (setf (conn-message-delay connection) 0)
                          (send-rex connection "(swank:throw-to-toplevel)" :thread (second debug))
                          ;; the loop of 3000 runs cannot end by itself within 10 s
                          (setf return (pump connection (return-of id) 10))))
               (is (and return (wire-symbol-p (first (second return)) "ABORT"))
                   "the loop did not end with the abort: ~s" return)))
           ;; the REPL still works, and no plan thread is left
           (let ((output (ok-output (repl-eval connection "(count-if (lambda (th) (uiop:string-prefix-p \"cpl \" (sb-thread:thread-name th))) (sb-thread:list-all-threads))"))))
             (is (equal "0" (value-line output)) "plan threads left after the abort: ~a" output)))
      (when first-connection (disconnect-swank first-connection))
      (when second-connection (disconnect-swank second-connection))
      (stop-swank-server server))))
