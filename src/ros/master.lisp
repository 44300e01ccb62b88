;;;; The ROS master: which URI to use, whether one answers there, and the error when none does.

(in-package :roslisp-utilities)

(define-condition ros-utilities-error (error)
  ((message :initarg :message :initform "" :reader ros-utilities-error-message))
  (:report (lambda (c s) (write-string (ros-utilities-error-message c) s)))
  (:documentation "Bad input to the ROS integration, or a ROS resource it needs is missing."))

(defun ros-fail (fmt &rest args)
  "Signal a ROS-UTILITIES-ERROR with the formatted message."
  (error 'ros-utilities-error :message (apply #'format nil fmt args)))

(define-condition ros-master-unreachable (ros-utilities-error)
  ((uri :initarg :uri :reader ros-master-unreachable-uri
        :documentation "The master URI that did not answer.")
   (source :initarg :source :reader ros-master-unreachable-source
           :documentation "Where the URI came from: :ARGUMENT, :ENVIRONMENT or :DEFAULT."))
  (:report (lambda (c s)
             (format s "No ROS master answers at ~a (~a). Start one (roscore, or roslaunch ~
                        launch/world.launch) or point ROS_MASTER_URI at a running master."
                     (ros-master-unreachable-uri c)
                     (ecase (ros-master-unreachable-source c)
                       (:argument "given as :MASTER-URI")
                       (:environment "from ROS_MASTER_URI")
                       (:default "the default; ROS_MASTER_URI is unset")))))
  (:documentation "STARTUP-ROS found no master at the URI it was to connect to."))

(setf (documentation 'ros-master-unreachable-uri 'function)
      "The master URI (a string) that a ROS-MASTER-UNREACHABLE condition reports."
      (documentation 'ros-master-unreachable-source 'function)
      "Where the URI of a ROS-MASTER-UNREACHABLE condition came from: :ARGUMENT, :ENVIRONMENT or :DEFAULT.")

(defparameter *default-ros-master-uri* "http://127.0.0.1:11311"
  "The master URI used when neither :MASTER-URI, roslisp:*default-master-uri* nor ROS_MASTER_URI give one.")

(defun roslisp-default-master-uri ()
  "roslisp:*default-master-uri* as a string when roslisp is loaded and it is set, else NIL."
  (let* ((package (find-package :roslisp))
         (symbol (and package (find-symbol "*DEFAULT-MASTER-URI*" package)))
         (value (and symbol (boundp symbol) (symbol-value symbol))))
    (cond ((null value) nil)
          ((stringp value) value)
          (t (format nil "http://~a:~a" (uiop:symbol-call :roslisp "URI-ADDRESS" value)
                     (uiop:symbol-call :roslisp "URI-PORT" value))))))

(defun ros-master-uri (&optional master-uri)
  "The master URI to connect to and where it came from, as (values uri-string source):
MASTER-URI when given (:ARGUMENT), else roslisp:*default-master-uri* when roslisp is loaded and
it is set (:ARGUMENT), else $ROS_MASTER_URI (:ENVIRONMENT), else http://127.0.0.1:11311 (:DEFAULT)."
  (let ((env (uiop:getenv "ROS_MASTER_URI"))
        (default (roslisp-default-master-uri)))
    (cond (master-uri (values master-uri :argument))
          (default (values default :argument))
          ((and env (plusp (length env))) (values env :environment))
          (t (values *default-ros-master-uri* :default)))))

(defun parse-master-uri (uri)
  "(values host port) of URI, a string http://HOST:PORT[/]; an error naming URI otherwise."
  (unless (stringp uri)
    (ros-fail "ROS master URI ~s, expected a string http://HOST:PORT" uri))
  (let* ((prefix "http://")
         (rest (and (uiop:string-prefix-p prefix uri)
                    (string-right-trim "/" (subseq uri (length prefix)))))
         (colon (and rest (position #\: rest :from-end t)))
         (host (and colon (subseq rest 0 colon)))
         (port (and colon (ignore-errors (parse-integer rest :start (1+ colon))))))
    (unless (and host (plusp (length host)) port (< 0 port 65536))
      (ros-fail "ROS master URI ~s, expected the form http://HOST:PORT (e.g. http://127.0.0.1:11311)" uri))
    (values host port)))

(defun loopback-host-p (host)
  "True when HOST names this machine's loopback interface."
  (or (string-equal host "localhost") (uiop:string-prefix-p "127." host) (string= host "::1")))

(defun call-with-timeout (timeout thunk)
  "THUNK's primary value when it returns within TIMEOUT seconds without an error, else NIL.
THUNK runs in its own thread, which is terminated when it overruns."
  (let* ((result nil)
         (thread (sb-thread:make-thread
                  (lambda () (setf result (ignore-errors (funcall thunk))))
                  :name "ROS master probe")))
    (handler-case (progn (sb-thread:join-thread thread :timeout timeout :default nil) result)
      (error () nil))
    (when (sb-thread:thread-alive-p thread)
      (ignore-errors (sb-thread:terminate-thread thread))
      (setf result nil))
    result))

(defparameter +get-pid-request+
  (concatenate 'string "<?xml version=\"1.0\"?><methodCall><methodName>getPid</methodName>"
               "<params><param><value><string>/roslisp_utilities_probe</string></value></param>"
               "</params></methodCall>")
  "The XML-RPC call ROS-AVAILABLE-P sends to the master.")

(defun master-get-pid-code (host port)
  "The status code of the master's answer to getPid at HOST:PORT (1 when it works), or NIL."
  (let ((socket (make-instance 'sb-bsd-sockets:inet-socket :type :stream :protocol :tcp)))
    (unwind-protect
         (progn
           (sb-bsd-sockets:socket-connect
            socket (first (sb-bsd-sockets:host-ent-addresses (sb-bsd-sockets:get-host-by-name host)))
            port)
           (let ((stream (sb-bsd-sockets:socket-make-stream socket :input t :output t
                                                                   :element-type 'character
                                                                   :external-format :latin-1
                                                                   :buffering :full)))
             (format stream "POST /RPC2 HTTP/1.0~c~cHost: ~a:~d~c~cContent-Type: text/xml~c~c~
                             Content-Length: ~d~c~c~c~c~a"
                     #\Return #\Newline host port #\Return #\Newline #\Return #\Newline
                     (length +get-pid-request+) #\Return #\Newline #\Return #\Newline
                     +get-pid-request+)
             (finish-output stream)
             (let* ((reply (with-output-to-string (out)
                             (loop for line = (read-line stream nil nil)
                                   while line do (write-line line out))))
                    (start (or (search "<int>" reply) (search "<i4>" reply))))
               (and (search "<methodResponse>" reply) start
                    (parse-integer reply :start (1+ (position #\> reply :start start))
                                         :junk-allowed t)))))
      (sb-bsd-sockets:socket-close socket))))

(defun ros-available-p (&key master-uri (timeout 2))
  "True when a ROS master answers an XML-RPC getPid call at MASTER-URI (default: see
ROS-MASTER-URI) within TIMEOUT seconds. Never hangs and never signals for an absent master; a
malformed MASTER-URI or TIMEOUT is an error. Needs no roslisp."
  (unless (and (realp timeout) (> timeout 0))
    (ros-fail "ROS-AVAILABLE-P: timeout ~s, expected a positive number of seconds" timeout))
  (multiple-value-bind (host port) (parse-master-uri (ros-master-uri master-uri))
    (eql 1 (call-with-timeout timeout (lambda () (master-get-pid-code host port))))))

(defun free-local-port ()
  "A TCP port of 127.0.0.1 that nothing listens on now (for a private master or node)."
  (let ((s (make-instance 'sb-bsd-sockets:inet-socket :type :stream :protocol :tcp)))
    (unwind-protect
         (progn (sb-bsd-sockets:socket-bind s #(127 0 0 1) 0)
                (nth-value 1 (sb-bsd-sockets:socket-name s)))
      (sb-bsd-sockets:socket-close s))))
