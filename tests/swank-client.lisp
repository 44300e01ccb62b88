;;;; A small client of the swank protocol (what SLIME speaks), for the tests of a user's day at
;;;; the REPL: a swank server in a child SBCL, connections that open, evaluate in the REPL,
;;;; collect the output, interrupt and disconnect as Emacs does.
;;;;
;;;; Wire format: six hexadecimal digits giving the length of the UTF-8 payload, then the
;;;; payload, one s-expression.

(defpackage :cram-plans-tests-repl
  (:use :cl :fiveam))

(in-package :cram-plans-tests-repl)

(defpackage :cram-plans-tests-swank-wire
  (:use)
  (:documentation "Symbols read from swank messages are interned here."))

(defun checkout-directory ()
  (namestring (asdf:system-source-directory "cram-plans/tests/base")))

(defun wait-for (seconds predicate &optional (step 0.05))
  "Call PREDICATE every STEP seconds until it returns true (its value) or SECONDS pass (NIL)."
  (loop with end = (+ (get-internal-real-time) (* seconds internal-time-units-per-second))
        for value = (funcall predicate)
        when value return value
        when (> (get-internal-real-time) end) return nil
        do (sleep step)))

;;; The server: a fresh SBCL in the checkout running swank, as a user's roslisp_repl or
;;; M-x slime-connect target does.

(defstruct swank-server process port log)

(defun start-swank-server ()
  "Start a child SBCL in the checkout that loads Debian's swank and serves it on a free port
\(the communication style :SPAWN, connections may come and go). Waits until it listens."
  (let* ((port (roslisp-utilities:free-local-port))
         (log (format nil "/tmp/cram-plans-swank-~d-~d.log" (sb-posix:getpid) port))
         (process (sb-ext:run-program
                   "sbcl" (list "--noinform" "--no-userinit" "--no-sysinit"
                                "--eval" "(require :asdf)"
                                "--eval" "(asdf:load-system \"swank\")"
                                "--eval" (format nil "(swank:create-server :port ~d :dont-close t)" port)
                                ;; ends itself when this process is gone
                                "--eval" (format nil "(loop (sleep 2) (unless (probe-file \"/proc/~d/\") (sb-ext:exit :abort t)))"
                                                 (sb-posix:getpid)))
                   :search t :wait nil :directory (checkout-directory)
                   :environment (remove-if (lambda (e) (uiop:string-prefix-p "CL_SOURCE_REGISTRY=" e))
                                           (sb-ext:posix-environ))
                   :input nil :output log :if-output-exists :supersede :error :output))
         (server (make-swank-server :process process :port port :log log)))
    (unless (wait-for 120 (lambda ()
                            (or (not (sb-ext:process-alive-p process))
                                (ignore-errors
                                 (sb-bsd-sockets:socket-close (open-swank-socket port))
                                 t)))
                      0.2)
      (let ((text (ignore-errors (uiop:read-file-string log))))
        (stop-swank-server server)
        (error "The swank server did not start listening on port ~d; its output:~%~a" port text)))
    server))

(defun stop-swank-server (server)
  "Kill the child SBCL of SERVER and remove its log."
  (let ((process (swank-server-process server)))
    (when (sb-ext:process-alive-p process)
      (sb-ext:process-kill process 9)
      (wait-for 10 (lambda () (not (sb-ext:process-alive-p process)))))
    (sb-ext:process-close process)
    (ignore-errors (delete-file (swank-server-log server)))))

;;; Connections

(defstruct (swank-connection (:conc-name conn-))
  socket stream (next-id 0) (messages '()) (output (make-string-output-stream))
  (message-delay 0) (package "COMMON-LISP-USER"))

(defun open-swank-socket (port)
  (let ((socket (make-instance 'sb-bsd-sockets:inet-socket :type :stream :protocol :tcp)))
    (handler-case (progn (sb-bsd-sockets:socket-connect socket #(127 0 0 1) port) socket)
      (error (e) (sb-bsd-sockets:socket-close socket) (error e)))))

(defun send-message (connection text)
  "Send TEXT, the printed form of one message, to the server."
  (let* ((octets (sb-ext:string-to-octets text :external-format :utf-8))
         (stream (conn-stream connection)))
    (write-sequence (sb-ext:string-to-octets (format nil "~6,'0x" (length octets))
                                             :external-format :latin-1)
                    stream)
    (write-sequence octets stream)
    (finish-output stream)))

(defun read-octets (stream n)
  (let* ((buffer (make-array n :element-type '(unsigned-byte 8)))
         (got (read-sequence buffer stream)))
    (when (< got n) (error 'end-of-file :stream stream))
    buffer))

(defun read-message (connection)
  "The next message from the server, read as a list (symbols in a scratch package)."
  (let* ((stream (conn-stream connection))
         (length (parse-integer (sb-ext:octets-to-string (read-octets stream 6)
                                                         :external-format :latin-1)
                                :radix 16))
         (text (sb-ext:octets-to-string (read-octets stream length) :external-format :utf-8)))
    (with-standard-io-syntax
      (let ((*package* (find-package :cram-plans-tests-swank-wire))
            (*read-eval* nil))
        (read-from-string text)))))

(defun wire-symbol-p (object name)
  (and (symbolp object) (string= (symbol-name object) name)))

(defun handle-message (connection message)
  "Record MESSAGE; collect user output; answer pings as Emacs does. MESSAGE-DELAY seconds per
output message stand for the time Emacs takes to insert it into the REPL buffer."
  (push message (conn-messages connection))
  (when (consp message)
    (let ((kind (first message)))
      (cond ((wire-symbol-p kind "WRITE-STRING")
             (write-string (second message) (conn-output connection))
             (when (plusp (conn-message-delay connection))
               (sleep (conn-message-delay connection))))
            ((wire-symbol-p kind "NEW-PACKAGE")
             ;; the REPL's package changed (IN-PACKAGE): later evaluations are read in it
             (setf (conn-package connection) (second message)))
            ((wire-symbol-p kind "PING")
             (send-message connection (format nil "(:emacs-pong ~s ~s)"
                                              (second message) (third message))))))))

(defun message-available-p (connection)
  (listen (conn-stream connection)))

(defun pump (connection predicate seconds)
  "Read and handle messages until PREDICATE (called with each message) returns true: returns
that message, or NIL after SECONDS."
  (let ((end (+ (get-internal-real-time) (* seconds internal-time-units-per-second))))
    (loop
      (when (> (get-internal-real-time) end) (return nil))
      (if (message-available-p connection)
          (let ((message (read-message connection)))
            (handle-message connection message)
            (when (funcall predicate message) (return message)))
          (sleep 0.01)))))

(defun connect-swank (server)
  "Open a connection to SERVER and set up its REPL as SLIME does on M-x slime-connect."
  (let* ((socket (open-swank-socket (swank-server-port server)))
         (connection (make-swank-connection
                      :socket socket
                      :stream (sb-bsd-sockets:socket-make-stream
                               socket :input t :output t :element-type '(unsigned-byte 8)
                                      :buffering :full))))
    (rex connection "(swank:connection-info)")
    (rex connection "(swank:swank-require '(swank-repl))")
    (rex connection "(swank-repl:create-repl nil)")
    connection))

(defun disconnect-swank (connection)
  "Close CONNECTION as M-x slime-disconnect does."
  (ignore-errors (close (conn-stream connection)))
  (ignore-errors (sb-bsd-sockets:socket-close (conn-socket connection))))

(defun send-rex (connection form &key (package "COMMON-LISP-USER") (thread t))
  "Send FORM (the text of a form, with package prefixes) for evaluation in THREAD (T, :REPL-THREAD
or a thread id), as Emacs's :emacs-rex; returns its request id."
  (let ((id (incf (conn-next-id connection))))
    (send-message connection (format nil "(:emacs-rex ~a ~s ~s ~d)" form package thread id))
    id))

(defun return-of (id)
  (lambda (message)
    (and (consp message) (wire-symbol-p (first message) "RETURN") (eql (car (last message)) id))))

(defun rex (connection form &key (package "COMMON-LISP-USER") (thread t) (seconds 300))
  "Evaluate FORM on the server and wait for its (:return ...); returns (status value), status
:OK or :ABORT. An unanswered request signals an error."
  (let* ((id (send-rex connection form :package package :thread thread))
         (message (pump connection
                        (lambda (message)
                          (or (funcall (return-of id) message) (debug-message-p message)))
                        seconds)))
    (cond ((null message)
           (error "No answer to ~a within ~d s." form seconds))
          ((debug-message-p message)
           (error "~a entered the debugger: ~s" form (subseq message 0 (min 5 (length message)))))
          (t (second message)))))

(defun debug-message-p (message)
  "True for the (:debug thread level condition restarts frames ...) message of SLDB."
  (and (consp message) (wire-symbol-p (first message) "DEBUG")))

(defun take-output (connection)
  "The user output collected on CONNECTION since the last call."
  (get-output-stream-string (conn-output connection)))

(defun repl-eval (connection text &key (seconds 300))
  "Type TEXT into CONNECTION's REPL and wait until it is evaluated; returns (status output)."
  (let ((result (rex connection (format nil "(swank-repl:listener-eval ~s)" (format nil "~a~%" text))
                     :package (conn-package connection) :thread :repl-thread :seconds seconds)))
    (list (first result) (take-output connection))))
